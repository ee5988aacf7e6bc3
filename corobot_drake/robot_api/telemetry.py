"""A robot's monitors: its signals (`signals.SIGNALS`), the wheels' contact telemetry, the
tip margin and tilt, the run log and the summary (`Robot` has these)."""

import dataclasses as dc
import math
from pathlib import Path

import numpy as np

from corobot_drake import signals
from corobot_drake.systems.runlog import (
    log_rows,
    max_tilt_deg,
    tip_margins,
    write_csv,
)


class RobotTelemetry:
    """Signals, contact telemetry, tip margin, the run log and the summary."""

    def signal(self, name: str):
        """The value now of the signal `name` (`signals.SIGNALS`): read from its port, or by
        its `reader`; a float, or a dict of floats by key (wheel, field or sensor name)."""
        spec = self._layout.signals[name]
        if spec.reader:
            value = getattr(self, spec.reader)()
            return dc.asdict(value) if dc.is_dataclass(value) else value
        return spec.value_of(self._sim.output_port(f"{self.name}.{spec.port}").Eval(
            self._sim.context))

    def wheel_loads(self) -> dict[str, float]:
        """Each wheel's load, N: the vertical component of its contact forces
        (`systems.contact`), by wheel name; at rest they sum to the robot's weight."""
        return self.signal("wheel_loads")

    def wheel_slip_ratio(self) -> dict[str, float]:
        """Each wheel's longitudinal slip ratio (`systems.contact`), by wheel name:
        (rim speed - ground speed) / the faster, + traction (the wheel turns faster than it
        travels, forwards or backwards), - braking; 0 at rest."""
        return self.signal("wheel_slip_ratio")

    def wheel_slip_angle(self) -> dict[str, float]:
        """Each wheel's slip angle, deg (`systems.contact`), by wheel name: atan2(its centre's
        speed across the heading (+ left), its speed along it); 0 at rest."""
        return self.signal("wheel_slip_angle")

    def tip_margin_deg(self) -> float:
        """How far (deg) the robot can still roll or pitch before its centre of mass passes
        an edge of the wheels' support polygon (`systems.stability`); upright on level
        ground 37.4 deg (pitch), negative while tipping over."""
        return self.signal("tip_margin")

    def min_tip_margin_deg(self) -> float:
        """The least `tip_margin_deg` so far, deg: over the run log's rows (every 10 ms; with
        `Simulation.run_log_window`, its window) and now."""
        sim = self._sim
        # From the samples' chassis alone: the contact telemetry need not be made.
        raw = sim._run_log_sink(self.name).FindLog(sim.context).data().T
        margins = [chunk[:, self._layout.columns.index("tip_margin")]
                   for chunk in sim._run_log_chunks[self.name]]
        margins.append(tip_margins(raw, self._tip_margin()))
        return float(min(min(m.min(initial=math.inf) for m in margins), self.tip_margin_deg()))

    def max_tilt_deg(self) -> float:
        """Largest tilt from upright so far, deg: over the run log's samples of the chassis
        (every 10 ms from the start, the whole run: `runlog.max_tilt_deg`), the start's
        included."""
        sim = self._sim
        log = sim._run_log_sink(self.name).FindLog(sim.context)
        return max(sim._max_tilt_moved_out[self.name], max_tilt_deg(log.data().T))

    @property
    def log_columns(self) -> tuple[str, ...]:
        """The names of the run log's columns (`run_log`'s and the CSV's): time, the signals'
        (its wheels' among them), then its sensors' (`SensorKind.log_columns`)."""
        return self._layout.columns

    def run_log(self):
        """The run log so far (numpy rows, columns `log_columns`: time, left_power,
        right_power, ..., then the sensors'), sampled every `runlog.LOG_PERIOD` s; with
        `Simulation.run_log_window`, only its last part."""
        sim = self._sim
        rows = log_rows(sim._run_log_sink(self.name), sim.context, self._tip_margin(),
                        sim._contact_samples, self.name, self._layout)
        chunks = sim._run_log_chunks[self.name]
        return np.concatenate([*chunks, rows]) if chunks else rows

    def _tip_margin(self):
        return self._sim.station.diagram.GetSubsystemByName(f"{self.name}.tip_margin")

    def write_log(self, path: str | Path) -> None:
        """Writes the run log as CSV (columns in docs/tuning.md; read by
        `corobot_drake.tuning.sysid`)."""
        write_csv(self.run_log(), path, self._layout)

    def telemetry(self) -> dict:
        """The contact telemetry now, as `summary` reports it (`signals.TELEMETRY`: each
        signal at its `summary` place)."""
        out: dict = {}
        for spec in signals.TELEMETRY:
            signals.put_value(out, spec.summary, self.signal(spec.name))
        return out

    def summary(self) -> dict:
        """The robot's figures now: every signal at its `summary` place (`signals.SIGNALS`:
        `wheel_loads_N` (N) and `slip`'s `ratio` and `angle_deg` lists are per wheel in
        the robot's wheel order, `RobotSpec.wheel_names`), the largest tilt, the frames
        saved, the least tip margin over the run (`min_tip_margin_deg`), each sensor's latest
        reading (`sensor_readings`) and the command log."""
        out: dict = {"max_tilt_deg": self.max_tilt_deg(),
                     "camera_frames": self.camera_frames_saved()}
        for spec in signals.SIGNALS.values():
            if spec.summary:
                signals.put_value(out, spec.summary, self.signal(spec.name))
        return {
            **out,
            "min_tip_margin_deg": self.min_tip_margin_deg(),
            "sensors": self.sensor_readings(summary=True),
            "commands": [
                {"command": r.command, "status": r.status, "reason": r.reason,
                 "start_time": r.start_time, "end_time": r.end_time}
                for r in self.command_log()
            ],
        }
