"""The HTTP face of a running simulation: `create_app(runner)` assembles the FastAPI app from
the resource routers in `routes` around a started `runner.Runner`.

The app runs in the HTTP server's event loop (uvicorn's thread, or the HTTP process); it reads
the runner's snapshot and sends everything else to the simulation thread through the runner.
"""

from __future__ import annotations

from fastapi import FastAPI
from fastapi.staticfiles import StaticFiles

from corobot_drake.serving.routes import ROUTERS, errors
from corobot_drake.serving.routes.backend import STATIC_DIR, Backend
from corobot_drake.serving.runner import Runner

API_DESCRIPTION = """\
The HTTP face of a running simulation (FastAPI): service directory, drive, analog-sensor,
encoder, compass, GPS and webcam contracts, Server-Sent Event subscriptions, the dashboard.

Every read is served from the runner's latest snapshot; every command goes through the
runner's queue to the simulation thread (`corobot_drake.serving.runner.SimRunner`). The OpenAPI
description is at /openapi.json, interactive docs at /docs.
"""
"""The OpenAPI document's description."""


def create_app(runner: Runner) -> FastAPI:
    """The FastAPI app serving `runner`'s simulation (started: its robots are known)."""
    app = FastAPI(title="corobot-drake live services", version="1",
                  description=API_DESCRIPTION)
    app.state.backend = Backend(runner)
    errors.install(app)
    for router in ROUTERS:
        app.include_router(router)
    app.mount("/static", StaticFiles(directory=STATIC_DIR), name="static")
    return app
