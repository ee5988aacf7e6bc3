"""Subscriptions: Server-Sent Events carrying a service's state each time it changes, checked
against the runner's latest snapshot every `period` s."""

from __future__ import annotations

import asyncio
import json
import time
from collections.abc import AsyncIterator, Callable
from typing import Annotated

from fastapi import APIRouter, HTTPException, Query, Request
from fastapi.responses import Response
from starlette.responses import StreamingResponse

from corobot_drake.serving.routes.backend import Backend, BackendDep

router = APIRouter(tags=["subscriptions"])

SUBSCRIPTION_CHECK_PERIOD = 0.1
"""s between checks of a subscription's readings (the contract promises at most 0.2 s)."""

SubscribePeriod = Annotated[float, Query(ge=0.02, le=0.2, description="s between checks")]
SubscribeLimit = Annotated[float | None, Query(gt=0, le=86400,
                                               description="close the stream after this many s")]


@router.get("/robots/{robot}/subscribe", response_class=Response,
            summary="Server-Sent Events: one event per service whose state changed")
async def subscribe_all(request: Request, robot: str, backend: BackendDep,
                        services: str | None = None,
                        period: SubscribePeriod = SUBSCRIPTION_CHECK_PERIOD,
                        limit: SubscribeLimit = None):
    names = services.split(",") if services else backend.subscribable(robot)
    return event_stream(request, backend, robot, names, period, limit)


@router.get("/robots/{robot}/{service}/subscribe", response_class=Response,
            summary="Server-Sent Events for one service (when its reading changes)")
async def subscribe(request: Request, robot: str, service: str, backend: BackendDep,
                    period: SubscribePeriod = SUBSCRIPTION_CHECK_PERIOD,
                    limit: SubscribeLimit = None):
    return event_stream(request, backend, robot, [service], period, limit)


def event_stream(request: Request, backend: Backend, robot: str, services: list[str],
                 period: float, limit: float | None) -> Response:
    """The stream of `services`' changes (404 for an unknown robot or service)."""
    extractors = {s: extractor(backend, robot, s) for s in services}
    return StreamingResponse(_events(request, backend, robot, extractors, period, limit),
                             media_type="text/event-stream",
                             headers={"Cache-Control": "no-store", "X-Accel-Buffering": "no"})


def extractor(backend: Backend, robot: str, service: str) -> Callable[[dict], dict]:
    """The function that picks `service`'s state out of a robot's snapshot."""
    subscribable = backend.subscribable(robot)
    if service not in subscribable:
        raise HTTPException(404, f"robot {robot!r} has no subscribable service {service!r}; "
                            f"services: {', '.join(subscribable)}")
    if service in ("drive", "encoders", "compass", "gps"):
        return lambda snap: snap[service]
    return lambda snap: snap["ir"][service]


async def _events(request: Request, backend: Backend, robot: str,
                  extractors: dict[str, Callable[[dict], dict]], period: float,
                  limit: float | None) -> AsyncIterator[str]:
    last: dict[str, str] = {}
    started = time.monotonic()
    yield "retry: 1000\n\n"
    while True:
        snap = backend.runner.snapshot["robots"][robot]
        for name, extract in extractors.items():
            state = extract(snap)
            key = _change_key(state)
            if last.get(name) != key:
                last[name] = key
                yield f"event: {name}\ndata: {json.dumps(state, allow_nan=False)}\n\n"
        if limit is not None and time.monotonic() - started > limit:
            return
        if await request.is_disconnected():
            return
        await asyncio.sleep(period)


def _change_key(state: dict) -> str:
    """A state's identity for change notification: everything but its time stamps."""
    return json.dumps({k: v for k, v in state.items() if k not in ("time", "time_stamp")},
                      sort_keys=True, default=str)
