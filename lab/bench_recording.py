"""What `--mcap` and `--record` cost (`tools/bench_recording.py`).

`recording_run(kind, seconds, out_dir)` simulates the default scene (IR and camera on, the
robot driving a circle) for `seconds` headless, as `python -m corobot_drake --headless` does:
plain, with the Foxglove topics written to MCAP (`mcap`), with the Meshcat replay (`record`,
an offline Meshcat and Drake's visualizers recording), or both. The wall time counts the run and
the file's writing (the MCAP's close, the HTML's), not the diagram's build.
"""

from __future__ import annotations

import time
from pathlib import Path

from corobot_drake.config.scenario import load_scenario
from corobot_drake.recording.mcap_log import McapLog
from corobot_drake.resources import DEFAULT_SCENARIO
from corobot_drake.simulation import Simulation, quiet_drake_warnings

CIRCLE = "robots: {corobot: {commands: [!SetPower {left: 0.4, right: 0.8}]}}"
KINDS = ("plain", "mcap", "record", "mcap+record")


def recording_run(kind: str, seconds: float, out_dir: str | Path) -> tuple[float, int]:
    """(wall seconds, bytes written) of one run of `kind` (one of `KINDS`)."""
    quiet_drake_warnings()
    out = Path(out_dir)
    mcap, html = out / f"{kind}.mcap", out / f"{kind}.html"
    log = McapLog(mcap) if "mcap" in kind else None
    sim = Simulation(load_scenario(DEFAULT_SCENARIO, overrides=[CIRCLE]),
                     record="record" in kind, foxglove=log.context if log else None)
    start = time.perf_counter()
    sim.advance(seconds)
    size = 0
    if log is not None:
        log.close()
        size += mcap.stat().st_size
    if "record" in kind:
        size += sim.save_recording(html)
    return time.perf_counter() - start, size
