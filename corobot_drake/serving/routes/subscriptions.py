"""Subscriptions: Server-Sent Events carrying a service's state each time it changes, checked
against the runner's latest snapshot every `period` s.

A change is a move beyond a threshold since the state last sent (`CHANGE_THRESHOLDS`; an IR
reading's is its sensor's `change_threshold`), so a robot at rest, which creeps by nanometres,
sends nothing; an optional `heartbeat` sends the state anyway when none was sent for that long.
"""

from __future__ import annotations

import asyncio
import json
import time
from collections.abc import AsyncIterator, Callable
from typing import Annotated

from fastapi import APIRouter, HTTPException, Query
from fastapi.responses import Response
from sse_starlette import EventSourceResponse

from corobot_drake import signals
from corobot_drake.serving.routes.backend import Backend, BackendDep

router = APIRouter(tags=["subscriptions"])

SUBSCRIPTION_CHECK_PERIOD = 0.1
"""s between checks of a subscription's readings (the contract promises at most 0.2 s)."""

SubscribePeriod = Annotated[float, Query(ge=0.02, le=0.2, description="s between checks")]
SubscribeLimit = Annotated[float | None, Query(gt=0, le=86400,
                                               description="close the stream after this many s")]
SubscribeHeartbeat = Annotated[float | None, Query(
    gt=0, le=3600, description="s: send a service's state anyway when none was sent for this "
    "long (default: only on changes)")]

CHANGE_THRESHOLDS = signals.change_thresholds()
"""A state's numbers by field name -> the change that counts (`signals.py`); any other field
(commanded power, encoder ticks, the command, ...) counts at any change. Time stamps never
count."""
IGNORED = ("time", "time_stamp")


@router.get("/robots/{robot}/subscribe", response_class=Response,
            summary="Server-Sent Events: one event per service whose state changed")
async def subscribe_all(robot: str, backend: BackendDep,
                        services: str | None = None,
                        period: SubscribePeriod = SUBSCRIPTION_CHECK_PERIOD,
                        limit: SubscribeLimit = None, heartbeat: SubscribeHeartbeat = None):
    names = services.split(",") if services else backend.subscribable(robot)
    return event_stream(backend, robot, names, period, limit, heartbeat)


@router.get("/robots/{robot}/{service}/subscribe", response_class=Response,
            summary="Server-Sent Events for one service (when its reading changes)")
async def subscribe(robot: str, service: str, backend: BackendDep,
                    period: SubscribePeriod = SUBSCRIPTION_CHECK_PERIOD,
                    limit: SubscribeLimit = None, heartbeat: SubscribeHeartbeat = None):
    return event_stream(backend, robot, [service], period, limit, heartbeat)


def event_stream(backend: Backend, robot: str, services: list[str], period: float,
                 limit: float | None, heartbeat: float | None = None) -> Response:
    """The stream of `services`' changes (404 for an unknown robot or service), framed by
    sse-starlette (lines end in LF, as the dashboard's reader splits them; it ends the stream
    when the client goes, and sends a comment line every 15 s, which clients skip)."""
    extractors = {s: extractor(backend, robot, s) for s in services}
    thresholds = {s: thresholds_of(backend, robot, s) for s in services}
    return EventSourceResponse(_events(backend, robot, extractors, thresholds, period, limit,
                                       heartbeat), sep="\n")


def extractor(backend: Backend, robot: str, service: str) -> Callable[[dict], dict]:
    """The function that picks `service`'s state out of a robot's snapshot."""
    subscribable = backend.subscribable(robot)
    if service not in subscribable:
        raise HTTPException(404, f"robot {robot!r} has no subscribable service {service!r}; "
                            f"services: {', '.join(subscribable)}")
    if service in ("drive", "encoders", "compass", "gps"):
        return lambda snap: snap[service]
    return lambda snap: snap["ir"][service]


def thresholds_of(backend: Backend, robot: str, service: str) -> dict[str, float]:
    """The change thresholds of `service`'s fields (an IR sensor's raw and normalized reading
    from its `change_threshold`)."""
    ir = dict(backend.robot(robot).ir_change_thresholds)
    if service in ir:
        return {**CHANGE_THRESHOLDS, "raw": ir[service], "normalized": 0.0}
    return CHANGE_THRESHOLDS


def changed(old, new, thresholds: dict[str, float], field: str = "") -> bool:
    """Whether `new` differs from `old` (JSON-like states) beyond the thresholds: a number
    by more than its field's threshold (IR `normalized` follows `raw`), anything else at all."""
    if isinstance(old, dict) and isinstance(new, dict):
        if old.keys() != new.keys():
            return True
        if "raw" in new and "normalized" in new and "raw" in thresholds:
            new = {k: v for k, v in new.items() if k != "normalized"}  # raw / range
        return any(changed(old[k], v, thresholds, k) for k, v in new.items()
                   if k not in IGNORED)
    if isinstance(old, list) and isinstance(new, list):
        return len(old) != len(new) or any(changed(a, b, thresholds, field)
                                           for a, b in zip(old, new, strict=True))
    numbers = (int, float)
    if (isinstance(old, numbers) and isinstance(new, numbers) and not isinstance(old, bool)
            and not isinstance(new, bool)):
        return abs(new - old) > thresholds.get(field, 0.0)
    return old != new


async def _events(backend: Backend, robot: str, extractors: dict[str, Callable[[dict], dict]],
                  thresholds: dict[str, dict[str, float]], period: float,
                  limit: float | None, heartbeat: float | None
                  ) -> AsyncIterator[dict]:
    """The stream's events, as sse-starlette's fields (`event`, `data`, `retry`)."""
    sent: dict[str, tuple[dict, float]] = {}  # service -> (state sent, monotonic time)
    started = time.monotonic()
    yield {"retry": 1000}
    while True:
        snap = backend.runner.snapshot["robots"].get(robot)
        if snap is None:  # the robot was deleted: the stream ends (a reconnection gets 404)
            return
        now = time.monotonic()
        for name, extract in extractors.items():
            state = extract(snap)
            last = sent.get(name)
            due = last is None or changed(last[0], state, thresholds[name]) or (
                heartbeat is not None and now - last[1] >= heartbeat)
            if due:
                sent[name] = (state, now)
                yield {"event": name, "data": json.dumps(state, allow_nan=False)}
        if limit is not None and now - started > limit:
            return
        await asyncio.sleep(period)
