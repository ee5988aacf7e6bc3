"""Sweeps the wheel contact parameters and recommends a setting (SPEC "Tuning ... by hand").

What each setting is measured on and how the recommendation is chosen:
`corobot_drake.analysis.tire_grip` (its docstring). Writes a CSV, a markdown table and a plot
(to --out), names the recommended setting, then checks its contact at 1, 2 and 5 ms.

Usage: python tools/tune_tire_grip.py [--quick] [--out out/tire_grip]
"""

import argparse
import dataclasses as dc
import sys
import time
from pathlib import Path

from corobot_drake.analysis.tire_grip import (
    SPIN_WHEEL_SPEED,
    Setting,
    default_sweep,
    measure,
    predicted_spin_rate,
    recommend,
    verdict,
    write_outputs,
)
from corobot_drake.config import scenario as sc
from corobot_drake.model import dimensions as dim
from corobot_drake.model.sdf import WheelContact
from corobot_drake.resources import DEFAULT_SCENARIO
from corobot_drake.simulation import quiet_drake_warnings

REPO = Path(__file__).resolve().parent.parent


def _sweep(args, robot: str, base_step: float) -> list[dict]:
    """Measures every setting of the sweep, printing a line for each; returns the rows."""
    sweep = [s for s in default_sweep(args.quick) if not args.only or args.only in s.label
             or s.label == "defaults"]
    defaults = dc.asdict(WheelContact())
    prediction = predicted_spin_rate(SPIN_WHEEL_SPEED * dim.WHEEL_RADIUS)
    print(f"tire grip sweep: {len(sweep)} settings around contact {defaults}, time step "
          f"{base_step * 1000:g} ms; spin prediction {prediction:.4f} rad/s", flush=True)
    rows = []
    for i, setting in enumerate(sweep, start=1):
        step = setting.plant.get("time_step", base_step)
        t0 = time.perf_counter()
        row = {"setting": setting.label, **measure(args.scenario, robot, setting, step,
                                                    args.box_seconds)}
        row["_setting"] = setting
        rows.append(row)
        passes, smooth = verdict(row)
        print(f"[{i}/{len(sweep)}] {setting.label}: yaw {row['yaw_ratio']:.3f} x prediction, "
              f"vz std {row['vz_std_mm_s']:.3f} mm/s, roll/pitch rate std "
              f"{row['roll_rate_std_deg_s']:.2f}/{row['pitch_rate_std_deg_s']:.2f} deg/s, tilt "
              f"{row['tilt_forwards_deg']:.1f}/{row['tilt_backwards_deg']:.1f} deg, top "
              f"{row['top_speed']:.4f} m/s, RTF {row['rtf_cpu']:.2f}x CPU "
              f"({row['rtf_wall']:.2f}x wall){'' if passes else '  FAILS'}"
              f"{'' if smooth else '  JITTERY'}  [{time.perf_counter() - t0:.0f} s]",
              flush=True)
    return rows


def _check(args, robot: str, setting: Setting) -> bool:
    """Measures `setting` at 1, 2 and 5 ms, printing a line for each; True if all pass."""
    print("check at 1, 2 and 5 ms:")
    ok = True
    for step in (0.001, 0.002, 0.005):
        checked = Setting(f"{setting.label} @ {step * 1000:g} ms", dict(setting.contact),
                          {**setting.plant, "time_step": step})
        row = measure(args.scenario, robot, checked, step, args.box_seconds)
        passes, _ = verdict(row)
        ok &= passes
        print(f"  {step * 1000:g} ms: yaw {row['yaw_ratio']:.3f} x prediction, tilt "
              f"{row['tilt_forwards_deg']:.1f}/{row['tilt_backwards_deg']:.1f} deg, roll/pitch "
              f"rate std {row['roll_rate_std_deg_s']:.2f}/{row['pitch_rate_std_deg_s']:.2f} "
              f"deg/s, RTF {row['rtf_cpu']:.2f}x CPU  {'ok' if passes else 'FAILS'}", flush=True)
    return ok


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--scenario", default=str(DEFAULT_SCENARIO))
    p.add_argument("--quick", action="store_true", help="3 settings (a smoke run)")
    p.add_argument("--only", help="run only settings whose label contains this text")
    p.add_argument("--box-seconds", type=float, default=4.0,
                   help="s of full power into the box (it is reached after ~1 s)")
    p.add_argument("--no-check", action="store_true",
                   help="skip checking the recommendation at 1, 2 and 5 ms")
    p.add_argument("--out", default=str(REPO / "out" / "tire_grip"),
                   help="output prefix: PREFIX.csv, PREFIX.md, PREFIX.png")
    args = p.parse_args(argv)
    quiet_drake_warnings()
    scenario = sc.load_scenario(args.scenario)
    robot = next(iter(scenario.robots))
    start = time.perf_counter()
    rows = _sweep(args, robot, scenario.plant_config.time_step)
    best = recommend(rows)
    out = Path(args.out)
    table = write_outputs(rows, best, out)
    print()
    print(table)
    print(f"wrote {out.with_suffix('.csv')}, {out.with_suffix('.md')}, {out.with_suffix('.png')}"
          f"  ({time.perf_counter() - start:.0f} s)")
    if best is None:
        print("recommended: none (every setting flips or misses the spin prediction)")
        return 1
    setting = best["_setting"]
    print(f"recommended: {setting.label}: contact {setting.contact or 'defaults'}, plant "
          f"{setting.plant or 'defaults'} (no flip, spin within 5%, "
          f"{'smooth' if verdict(best)[1] else 'least jitter'}, fastest)")
    if args.no_check:
        return 0
    return 0 if _check(args, robot, setting) else 1


if __name__ == "__main__":
    sys.exit(main())
