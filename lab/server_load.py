"""A load on a served simulation: clients polling state and a flood of malformed requests.

`tests/service/test_server.py` asserts that every request of it is answered while the
simulation goes on; `tools/bench_server_flood.py` measures the real-time factor the server
keeps under it (`measure`).
"""

from __future__ import annotations

import concurrent.futures
import contextlib
import dataclasses as dc
import os
import threading
import time

import httpx

MALFORMED = (
    ("POST", "{robot}/drive/set_power", "{"),
    ("POST", "{robot}/drive/set_power", '{"left": NaN, "right": 0}'),
    ("POST", "{robot}/drive/set_power", '{"left": 7, "right": 0}'),
    ("POST", "{robot}/drive/set_speed", '{"left": "x"}'),
    ("POST", "/robots/ghost/drive/set_power", '{"left": 0, "right": 0}'),
    ("GET", "{robot}/warp_drive", None),
    ("POST", "{robot}/drive/enable", "\x00\xff garbage"),
    ("DELETE", "{robot}/drive", None),
)
"""(method, path with `{robot}`, body) of the flood's requests: each must get a 4xx."""


@dc.dataclass
class Answers:
    """What the load got back."""

    flood_codes: list[int]
    """The status code of every malformed request."""
    polls_ok: int
    polls_bad: int
    """Polls answered 200, and otherwise."""
    wall_seconds: float
    """s from the load's start to its end."""


def _background() -> None:
    """The load's clients stand for browsers on other machines: on this one they must not take
    the simulation's CPU (Linux threads have their own nice value)."""
    with contextlib.suppress(OSError, AttributeError):
        os.setpriority(os.PRIO_PROCESS, threading.get_native_id(), 10)


def run(url: str, robot: str, poll_paths: list[str], pollers: int = 20, floods: int = 2,
        per_flood: int = 500, polls_each: int = 10, timeout: float = 60.0) -> Answers:
    """`pollers` clients each polling `poll_paths` in turn every 0.1 s, while `floods`
    clients send `per_flood` malformed requests each (`MALFORMED`, every 5 ms); then waits
    until every poller has had `polls_each` answers (TimeoutError after `timeout` s) and
    stops them. `robot` is the robot's path (`/robots/<name>`)."""
    stop, lock = threading.Event(), threading.Lock()
    polls = {"ok": 0, "bad": 0}

    def poller(i: int) -> None:
        _background()
        with httpx.Client(base_url=url, timeout=30) as client:
            n = 0
            while not stop.is_set():
                r = client.get(poll_paths[(i + n) % len(poll_paths)])
                n += 1
                with lock:
                    polls["ok" if r.status_code == 200 else "bad"] += 1
                time.sleep(0.1)

    def flood(k: int) -> list[int]:
        _background()
        codes = []
        with httpx.Client(base_url=url, timeout=30) as client:
            for j in range(per_flood):
                method, path, body = MALFORMED[(k * per_flood + j) % len(MALFORMED)]
                codes.append(client.request(method, path.format(robot=robot), content=body,
                                            headers={"Content-Type": "application/json"})
                             .status_code)
                time.sleep(0.005)
        return codes

    start = time.monotonic()
    threads = [threading.Thread(target=poller, args=(i,)) for i in range(pollers)]
    for t in threads:
        t.start()
    try:
        with concurrent.futures.ThreadPoolExecutor(floods) as pool:
            codes = [c for chunk in pool.map(flood, range(floods)) for c in chunk]
        deadline = time.monotonic() + timeout
        while True:
            with lock:
                answered = polls["ok"] + polls["bad"]
            if answered > pollers * polls_each:
                break
            if time.monotonic() > deadline:
                raise TimeoutError(f"{answered} polls answered in {timeout:g} s")
            time.sleep(0.1)
    finally:
        stop.set()
        for t in threads:
            t.join()
    return Answers(codes, polls["ok"], polls["bad"], time.monotonic() - start)


ROBOT = "/robots/corobot"
"""The default scenario's robot's path."""
POLL_PATHS = [f"{ROBOT}/drive", f"{ROBOT}/drive/two_wheel", f"{ROBOT}/encoders", "/services",
              f"{ROBOT}/front_ir", f"{ROBOT}/rear_ir"]
"""What the pollers read of the default robot."""


@dc.dataclass
class Rates:
    """Real-time factors of a server running in real time (simulated s per wall s)."""

    quiet: float
    """Over `quiet_seconds` with no client but the measuring one."""
    loaded: float
    """Over the load (`run`), from its start to its end."""
    answers: Answers


def _sim_time(client: httpx.Client) -> float:
    return float(client.get("/simulation").json()["time"])


def _rate(client: httpx.Client, during) -> tuple[float, object]:
    """(simulated s per wall s while `during()` runs, what it returned)."""
    t0, w0 = _sim_time(client), time.monotonic()
    result = during()
    return (_sim_time(client) - t0) / (time.monotonic() - w0), result


def measure(quiet_seconds: float = 10.0) -> Rates:
    """The default scenario served headless in real time (`ServerProcess`, stopped by its
    handle at the end), the robot spinning in place: its real-time factor with no load over
    `quiet_seconds`, then under `run`'s load."""
    from corobot_drake.serving.serve import ServerProcess

    with ServerProcess(["--headless"]) as server, \
            httpx.Client(base_url=server.url, timeout=60) as client:
        client.post(f"{ROBOT}/drive/set_power", json={"left": 0.3, "right": -0.3})
        time.sleep(2.0)  # past the start-up's first steps
        quiet, _ = _rate(client, lambda: time.sleep(quiet_seconds))
        loaded, answers = _rate(client, lambda: run(server.url, ROBOT, POLL_PATHS))
        return Rates(quiet, loaded, answers)
