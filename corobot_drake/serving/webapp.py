"""The HTTP face of a running simulation: `create_app(runner)` assembles the FastAPI app from
the resource routers in `routes` around a started `runner.Runner`.

The app runs in the HTTP server's event loop (uvicorn's thread, or the HTTP process); it reads
the runner's snapshot and sends everything else to the simulation thread through the runner.
"""

from __future__ import annotations

from fastapi import FastAPI
from fastapi.staticfiles import StaticFiles
from fastapi_offline import FastAPIOffline

from corobot_drake.serving.http_limits import RequestLimits
from corobot_drake.serving.routes import ROUTERS, errors
from corobot_drake.serving.routes.backend import STATIC_DIR, Backend
from corobot_drake.serving.runner import Runner
from corobot_drake.serving.security import Access, AccessGuard

API_DESCRIPTION = """\
The HTTP face of a running simulation (FastAPI): service directory, drive, analog-sensor,
encoder, compass, GPS and webcam contracts, Server-Sent Event subscriptions, the dashboard.

Every read is served from the runner's latest snapshot; every command goes through the
runner's queue to the simulation thread (`corobot_drake.serving.runner.SimRunner`). The OpenAPI
description is at /openapi.json, interactive docs at /docs and /redoc (served from this server:
they work offline).

A server on an address other than loopback (or started with `--token`) needs
`Authorization: Bearer <token>` on every request (in /docs: the Authorize button); every
POST needs a JSON body (`Content-Type: application/json`).
"""
"""The OpenAPI document's description."""


def create_app(runner: Runner, access: Access | None = None) -> FastAPI:
    """The FastAPI app serving `runner`'s simulation (started: its robots are known), behind
    `access`'s rules (`security`; default: loopback, no token)."""
    access = access or Access()
    # FastAPIOffline: /docs and /redoc load Swagger UI and ReDoc from this server, not a CDN.
    app = FastAPIOffline(title="corobot-drake live services", version="1",
                         description=API_DESCRIPTION)
    app.state.backend = Backend(runner)
    app.state.access = access
    errors.install(app)
    for router in ROUTERS:
        app.include_router(router)
    app.mount("/static", StaticFiles(directory=STATIC_DIR), name="static")
    app.add_middleware(AccessGuard, access=access)
    app.add_middleware(RequestLimits)  # added last: it runs first, before any access check
    _declare_bearer(app)
    return app


def _declare_bearer(app: FastAPI) -> None:
    """The OpenAPI document names the bearer token (optional on a loopback server without
    one), so /docs shows an Authorize button and clients know the scheme."""
    build = app.openapi

    def openapi() -> dict:
        if app.openapi_schema is None:
            schema = build()
            schema.setdefault("components", {})["securitySchemes"] = {"bearer": {
                "type": "http", "scheme": "bearer",
                "description": "the token the server printed (needed off loopback)"}}
            schema["security"] = [{"bearer": []}, {}]
        return app.openapi_schema

    app.openapi = openapi
