"""The resident memory of `--serve` over a long run (memory stays flat).

`measure()` starts the default scenario served headless (`serve.serve`, in a child process,
at a `rate` the machine cannot keep, so it runs as fast as it can), with clients on it the
whole time: a poller reading the drive state, the simulation and the robot at `poll_hz`, a
driver sending a set_power (and now and then a drive_distance) every `command_period` s, and
a camera frame every second. It samples the resident memory (VmRSS) of the server's process
tree (the simulation process and its HTTP process) against simulated time, and reports the
growth from the end of a warm-up to the end, and the slope over the second half (which, the
bounded logs full by then, is what an endless run adds).
"""

from __future__ import annotations

import dataclasses as dc
import math
import os
import subprocess
import sys
import threading
import time
from pathlib import Path

from lab.processes import descendants

SERVE_RATE = 40.0
"""Simulated s per wall s asked of the served simulation: more than this machine manages,
so it runs flat out (below `SimRunner`'s max_lag / tick = 60, where it would not step)."""


def serve_child(rate: float = SERVE_RATE) -> int:
    """The server process (run by `measure` as `python -c ...`): the default scenario served
    headless on a free loopback port at `rate`, as `python -m corobot_drake --serve` does."""
    from corobot_drake.config.scenario import load_scenario
    from corobot_drake.resources import DEFAULT_SCENARIO
    from corobot_drake.serving.serve import serve, serve_camera_rate
    from corobot_drake.simulation import Simulation, quiet_drake_warnings

    quiet_drake_warnings()
    scenario = load_scenario(DEFAULT_SCENARIO)
    serve_camera_rate(scenario)
    return serve(lambda meshcat: Simulation(scenario, meshcat), port=0, rate=rate)


def rss_bytes(pid: int) -> int:
    """Resident memory of process `pid` and all its descendants, bytes (0 once gone). The
    descendants come from every process's parent (`lab.processes`): a thread's `children` list
    would vanish with the thread, which the server starts and ends all the time."""
    total = 0
    for process in [pid, *descendants(pid)]:
        try:
            status = Path(f"/proc/{process}/status").read_text()
        except OSError:
            continue
        total += next((int(line.split()[1]) * 1024 for line in status.splitlines()
                       if line.startswith("VmRSS:")), 0)
    return total


@dc.dataclass
class Sample:
    sim_time: float
    """s."""
    rss: int
    """bytes."""


@dc.dataclass
class Result:
    samples: list[Sample]
    warmup: float
    """Simulated s before the growth is counted."""
    polls: int
    commands: int
    errors: int

    def at(self, t: float) -> Sample:
        """The first sample at or after simulated time t (the last one if none)."""
        return next((s for s in self.samples if s.sim_time >= t), self.samples[-1])

    @property
    def growth(self) -> float:
        """MB from the end of the warm-up to the end."""
        return (self.samples[-1].rss - self.at(self.warmup).rss) / 1e6

    @property
    def slope_per_hour(self) -> float:
        """MB per simulated hour over the second half of the run after the warm-up (the
        least-squares line through its samples)."""
        start = self.warmup + (self.samples[-1].sim_time - self.warmup) / 2
        tail = [s for s in self.samples if s.sim_time >= start]
        if len(tail) < 2:
            return math.nan
        mt = sum(s.sim_time for s in tail) / len(tail)
        mr = sum(s.rss for s in tail) / len(tail)
        num = sum((s.sim_time - mt) * (s.rss - mr) for s in tail)
        den = sum((s.sim_time - mt) ** 2 for s in tail)
        return num / den * 3600.0 / 1e6 if den > 0 else math.nan

    @property
    def simulated(self) -> float:
        return self.samples[-1].sim_time - self.samples[0].sim_time

    def hour_growth(self) -> float:
        """MB over one simulated hour after the warm-up: measured if the run was that long,
        else the growth so far plus the slope for the rest of the hour."""
        measured = self.samples[-1].sim_time - self.warmup
        if measured >= 3600.0:
            return (self.at(self.warmup + 3600.0).rss - self.at(self.warmup).rss) / 1e6
        return self.growth + self.slope_per_hour * (3600.0 - measured) / 3600.0


def _start_server(rate: float) -> tuple[subprocess.Popen, str]:
    code = ("import sys; from lab.bench_memory import serve_child; "
            f"sys.exit(serve_child({rate!r}))")
    process = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE,
                               stderr=subprocess.DEVNULL, text=True)
    line = process.stdout.readline()
    if not line.startswith("serving "):
        process.kill()
        raise RuntimeError(f"the server did not start: {line!r}")
    threading.Thread(target=process.stdout.read, daemon=True).start()
    return process, line.split()[1]


def _clients(url: str, stop: threading.Event, poll_hz: float, command_period: float,
             counts: dict) -> list[threading.Thread]:
    import random

    import httpx

    robot = f"{url}/robots/corobot"

    def poller() -> None:
        with httpx.Client(timeout=30) as http:
            while not stop.is_set():
                for path in (f"{robot}/drive", f"{url}/simulation", robot):
                    ok = http.get(path).status_code == 200
                    counts["polls" if ok else "errors"] += 1
                stop.wait(1.0 / poll_hz)

    def driver() -> None:
        rng = random.Random(1)
        with httpx.Client(timeout=60) as http:
            while not stop.is_set():
                if rng.random() < 0.1:  # now and then a command that completes
                    r = http.post(f"{robot}/drive/drive_distance",
                                  json={"distance": rng.uniform(-0.3, 0.3), "power": 0.5,
                                        "wait": False})
                else:
                    r = http.post(f"{robot}/drive/set_power", json={
                        "left": rng.uniform(-0.6, 0.6), "right": rng.uniform(-0.6, 0.6)})
                if rng.random() < 0.05:  # and back to the middle of the room
                    http.post(f"{robot}/drive/set_pose", json={"x": 2.0, "y": 0.0,
                                                               "wait": False})
                counts["commands" if r.status_code in (200, 202) else "errors"] += 1
                if rng.random() < 0.2:
                    http.get(f"{robot}/camera/frame.jpg")
                stop.wait(command_period)

    return [threading.Thread(target=f, daemon=True) for f in (poller, driver)]


def measure(sim_minutes: float = 60.0, warmup_minutes: float = 2.0, poll_hz: float = 10.0,
            command_period: float = 0.2, sample_every: float = 30.0, rate: float = SERVE_RATE,
            progress=None) -> Result:
    """Serves for `sim_minutes` of simulated time with the clients on; samples the server's
    resident memory every `sample_every` simulated s. `progress(sample)` after each."""
    import httpx

    process, url = _start_server(rate)
    stop = threading.Event()
    counts = {"polls": 0, "commands": 0, "errors": 0}
    threads = _clients(url, stop, poll_hz, command_period, counts)
    samples: list[Sample] = []
    try:
        for t in threads:
            t.start()
        with httpx.Client(timeout=30) as http:
            t0 = http.get(f"{url}/simulation").json()["time"]
            next_sample = t0
            while True:
                now = http.get(f"{url}/simulation").json()["time"]
                if now >= next_sample:
                    samples.append(Sample(now - t0, rss_bytes(process.pid)))
                    next_sample = now + sample_every
                    if progress is not None:
                        progress(samples[-1])
                if now - t0 >= sim_minutes * 60.0:
                    break
                if process.poll() is not None:
                    raise RuntimeError(f"the server stopped (exit {process.returncode})")
                time.sleep(0.5)
    finally:
        stop.set()
        for t in threads:
            t.join(10)
        if process.poll() is None:
            process.send_signal(2)  # SIGINT: the server's own clean stop
            try:
                process.wait(30)
            except subprocess.TimeoutExpired:
                process.kill()
    return Result(samples, warmup_minutes * 60.0, counts["polls"], counts["commands"],
                  counts["errors"])


def summary(result: Result, args: str) -> str:
    """One paragraph (the docs' generated block)."""
    load = os.getloadavg()[0]
    first = result.at(result.warmup)
    return (f"`--serve` of the default scenario (headless, camera at 10 Hz) for "
            f"{result.simulated / 60:.0f} simulated minutes flat out, a client polling state "
            f"({result.polls} polls) and one driving ({result.commands} commands; "
            f"{result.errors} errors): resident memory of the server's two processes "
            f"{first.rss / 1e6:.0f} MB after {result.warmup / 60:.0f} min, "
            f"{result.samples[-1].rss / 1e6:.0f} MB at the end ({result.growth:+.1f} MB); over "
            f"the second half {result.slope_per_hour:+.1f} MB per simulated hour; one simulated "
            f"hour: {result.hour_growth():+.1f} MB"
            + ("" if result.simulated >= 3600.0 + result.warmup else
               " extrapolated with that slope (an upper bound: the command log, still filling "
               "then, stops at its cap)")
            + f" (target: under 10). Load average {load:.1f} at the end ({args}).")
