"""The HTTP face of a running simulation (FastAPI): service directory, drive, analog-sensor,
encoder, compass, GPS and webcam contracts, Server-Sent Event subscriptions, the dashboard.

Every read is served from the runner's latest snapshot; every command goes through the
runner's queue to the simulation thread (`corobot_drake.serving.services.SimRunner`). The OpenAPI
description is at /openapi.json, interactive docs at /docs.
"""

from __future__ import annotations

import asyncio
import contextlib
import html
import io
import json
import time
from functools import partial
from pathlib import Path
from typing import Annotated, Any

from fastapi import FastAPI, HTTPException, Query, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import HTMLResponse, RedirectResponse, Response
from fastapi.staticfiles import StaticFiles
from starlette.exceptions import HTTPException as StarletteHTTPException

from corobot_drake.serving import schemas
from corobot_drake.serving import services as sv
from corobot_drake.serving.services import SimRunner

STATIC_DIR = Path(__file__).resolve().parent / "static"
SUBSCRIPTION_CHECK_PERIOD = 0.1
"""s between checks of a subscription's readings (the contract promises at most 0.2 s)."""
CAMERA_MAX_RATE = 15.0
"""Hz: frames are rendered on request, at most this often (simulated time)."""

SubscribePeriod = Annotated[float, Query(ge=0.02, le=0.2, description="s between checks")]
SubscribeLimit = Annotated[float | None, Query(gt=0, le=86400,
                                               description="close the stream after this many s")]
CameraInterval = Annotated[int, Query(ge=20, le=60000, description="refresh interval, ms")]

_ERRORS = schemas.ERRORS


def _json(content: Any, status_code: int = 200) -> Response:
    return Response(json.dumps(content, allow_nan=False), status_code=status_code,
                    media_type="application/json")


def _describe_errors(errors: list[dict]) -> str:
    parts = []
    for e in errors:
        loc = ".".join(str(x) for x in e.get("loc", ()) if x != "body") or "body"
        msg = e.get("msg", "invalid")
        if e.get("type") == "json_invalid":
            return f"malformed JSON: {e.get('ctx', {}).get('error', msg)}"
        if e.get("type") == "missing":
            parts.append(f"{loc}: required")
        elif "input" in e and e.get("type") != "extra_forbidden":
            parts.append(f"{loc}: {msg} (got {_short(e['input'])})")
        elif e.get("type") == "extra_forbidden":
            parts.append(f"{loc}: unknown field")
        else:
            parts.append(f"{loc}: {msg}")
    return "; ".join(parts) or "invalid request"


def _short(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


# --- the app ------------------------------------------------------------------------------


def create_app(runner: SimRunner, meshcat_url: str | None = None) -> FastAPI:
    """The FastAPI app serving `runner`'s simulation."""
    app = FastAPI(
        title="corobot-drake live services",
        version="1",
        description=__doc__,
    )
    app.state.runner = runner
    if not runner.capabilities:
        raise ValueError("start the runner before creating its app")
    robot_names = list(runner.capabilities)
    caps = runner.capabilities
    camera_cache: dict[str, dict] = {}

    # --- errors: always {"detail": "<one clear sentence>"} ---
    @app.exception_handler(RequestValidationError)
    async def _validation_error(request: Request, exc: RequestValidationError):
        errors = exc.errors()
        message = _describe_errors(errors)
        status = 400 if message.startswith("malformed JSON") else 422
        return _json({"detail": message}, status)

    @app.exception_handler(StarletteHTTPException)
    async def _http_error(request: Request, exc: StarletteHTTPException):
        detail = exc.detail if isinstance(exc.detail, str) else json.dumps(exc.detail)
        if exc.status_code == 404 and detail == "Not Found":
            detail = f"no such resource: {request.url.path} (the service directory is /services)"
        if exc.status_code == 405:
            detail = f"{request.method} is not allowed on {request.url.path}"
        return _json({"detail": detail}, exc.status_code)

    # --- helpers ---
    def robot_or_404(robot: str) -> str:
        if robot not in caps:
            raise HTTPException(404, f"no robot named {robot!r}; robots: "
                                f"{', '.join(robot_names)}")
        return robot

    def snapshot_of(robot: str) -> dict:
        robot_or_404(robot)
        return runner.snapshot["robots"][robot]

    def require(robot: str, capability: str) -> None:
        if not caps[robot][capability]:
            raise HTTPException(501, f"{capability} is not available in this build of the "
                                "simulation")

    async def in_sim(fn, timeout: float = 10.0):
        if not runner.alive:
            raise HTTPException(503, "the simulation is not running")
        future = runner.submit(fn)
        try:
            return await asyncio.wait_for(asyncio.wrap_future(future), timeout)
        except TimeoutError:
            raise HTTPException(503, "the simulation did not answer in time") from None
        except (ValueError, KeyError, TypeError) as e:
            raise HTTPException(422, str(e).strip("'\"")) from None

    def services_of(robot: str) -> list[dict]:
        base = f"/robots/{robot}"
        drive_ops = ["set_power", "set_speed", "all_stop", "enable"]
        drive_ops += [op for op in ("drive_distance", "rotate_degrees", "set_pose")
                      if caps[robot][op]]
        out = [dict(robot=robot, name="drive", contract=sv.CONTRACT_DRIVE,
                    state_url=f"{base}/drive", subscribe_url=f"{base}/drive/subscribe",
                    operations=drive_ops)]
        for name in runner.snapshot["robots"][robot]["ir"]:
            out.append(dict(robot=robot, name=name, contract=sv.CONTRACT_ANALOG_SENSOR,
                            state_url=f"{base}/{name}", subscribe_url=f"{base}/{name}/subscribe"))
        out.append(dict(robot=robot, name="encoders", contract=sv.CONTRACT_ENCODERS,
                        state_url=f"{base}/encoders", subscribe_url=f"{base}/encoders/subscribe"))
        out.append(dict(robot=robot, name="compass", contract=sv.CONTRACT_COMPASS,
                        state_url=f"{base}/compass", subscribe_url=f"{base}/compass/subscribe"))
        out.append(dict(robot=robot, name="gps", contract=sv.CONTRACT_GPS,
                        state_url=f"{base}/gps", subscribe_url=f"{base}/gps/subscribe"))
        if caps[robot]["camera"]:
            out.append(dict(robot=robot, name="camera", contract=sv.CONTRACT_WEBCAM,
                            state_url=f"{base}/camera", page_url=f"{base}/camera/page",
                            operations=["frame.png", "frame.jpg"]))
        return out

    def service_names(robot: str) -> list[str]:
        return [s["name"] for s in services_of(robot)]

    # --- pages ---
    @app.get("/", include_in_schema=False)
    async def root():
        return RedirectResponse("/dashboard")

    @app.get("/dashboard", response_class=HTMLResponse, tags=["pages"],
             summary="The dashboard: drive pad, IR gauges, pose, encoders, camera")
    async def dashboard():
        return HTMLResponse((STATIC_DIR / "dashboard.html").read_text())

    @app.get("/services", response_model=schemas.Directory, tags=["directory"],
             summary="Every robot's services (JSON; HTML for browsers or with ?format=html)")
    async def services(request: Request, format: str | None = None):
        entries = [s for r in robot_names for s in services_of(r)]
        want_html = format == "html" or (
            format is None and "text/html" in request.headers.get("accept", ""))
        if format not in (None, "html", "json"):
            raise HTTPException(422, f"format must be html or json, got {format!r}")
        if want_html:
            return HTMLResponse(_directory_html(entries, meshcat_url))
        return _json({"services": entries, "simulation_url": "/simulation",
                      "dashboard_url": "/dashboard", "meshcat_url": meshcat_url})

    @app.get("/simulation", tags=["directory"],
             summary="Simulation time, real-time factor, runner statistics")
    async def simulation():
        stats = runner.stats()
        stats["robots"] = robot_names
        stats["meshcat_url"] = meshcat_url
        return _json(stats)

    @app.get("/robots", tags=["directory"], summary="Robot names")
    async def robots():
        return _json({"robots": robot_names})

    @app.get("/robots/{robot}", tags=["directory"], summary="One robot's services and state")
    async def robot_root(robot: str):
        return _json({"robot": robot, "services": services_of(robot_or_404(robot)),
                      "capabilities": caps[robot], "state": snapshot_of(robot)})

    # --- drive contract ---
    @app.get("/robots/{robot}/drive", response_model=schemas.DriveState, responses=_ERRORS,
             tags=["drive"], summary="Four-wheel drive state")
    async def get_drive(robot: str):
        return _json(snapshot_of(robot)["drive"])

    @app.get("/robots/{robot}/drive/two_wheel", response_model=schemas.TwoWheelState,
             responses=_ERRORS, tags=["drive"],
             summary="Two-wheel view (left = front left, right = front right)")
    async def get_two_wheel(robot: str):
        return _json(sv.two_wheel_view(snapshot_of(robot)["drive"]))

    async def simple_command(robot: str, name: str, *args) -> Response:
        robot_or_404(robot)
        seq, t = await in_sim(partial(sv.call_robot, robot, name, args))
        return _json({"robot": robot, "command": name,
                      "seq": seq if isinstance(seq, int) else None,
                      "status": "accepted", "time": t})

    @app.post("/robots/{robot}/drive/set_power", response_model=schemas.Accepted, responses=_ERRORS,
              tags=["drive"], summary="Power per side in [-1, 1]")
    async def set_power(robot: str, body: schemas.PowerRequest):
        return await simple_command(robot, "set_power", body.left, body.right)

    @app.post("/robots/{robot}/drive/set_speed", response_model=schemas.Accepted, responses=_ERRORS,
              tags=["drive"], summary="Rim speed per side, m/s")
    async def set_speed(robot: str, body: schemas.SpeedRequest):
        return await simple_command(robot, "set_speed", body.left, body.right)

    @app.post("/robots/{robot}/drive/all_stop", response_model=schemas.Accepted, responses=_ERRORS,
              tags=["drive"], summary="Both sides to zero speed")
    async def all_stop(robot: str, body: schemas.EmptyRequest | None = None):
        return await simple_command(robot, "all_stop")

    @app.post("/robots/{robot}/drive/enable", response_model=schemas.Accepted, responses=_ERRORS,
              tags=["drive"], summary="Enable or disable the drive")
    async def enable(robot: str, body: schemas.EnableRequest):
        return await simple_command(robot, "enable", body.enabled)

    async def completing(robot: str, name: str, arguments: dict, wait: bool,
                         timeout: float) -> Response:
        robot_or_404(robot)
        require(robot, name)
        future = runner.start_operation(robot, name, arguments)
        if not runner.alive:
            raise HTTPException(503, "the simulation is not running")
        try:
            op = await asyncio.wait_for(asyncio.wrap_future(future), 10.0)
        except (ValueError, KeyError, TypeError) as e:
            raise HTTPException(422, str(e).strip("'\"")) from None
        url = f"/robots/{robot}/drive/operations/{op.id}"
        if wait and op.status == "running":
            with contextlib.suppress(TimeoutError):
                op = await asyncio.wait_for(asyncio.shield(asyncio.wrap_future(
                    runner.operation_done(op.id))), timeout)
        body = {**op.public(), "status_url": url}
        code = 200 if op.status != "running" else 202
        return Response(json.dumps(sv._jsonable(body)), status_code=code,
                        media_type="application/json", headers={"Location": url})

    @app.post("/robots/{robot}/drive/drive_distance", response_model=schemas.OperationState,
              responses={**_ERRORS, 202: {"model": schemas.OperationState}}, tags=["drive"],
              summary="Drive straight |distance| m (negative: backwards); completes")
    async def drive_distance(robot: str, body: schemas.DriveDistanceRequest):
        args = {"distance": body.distance, "power": body.power}
        return await completing(robot, "drive_distance", args, body.wait, body.timeout)

    @app.post("/robots/{robot}/drive/rotate_degrees", response_model=schemas.OperationState,
              responses={**_ERRORS, 202: {"model": schemas.OperationState}}, tags=["drive"],
              summary="Turn in place (positive: left, counter-clockwise); completes")
    async def rotate_degrees(robot: str, body: schemas.RotateDegreesRequest):
        args = {"degrees": body.degrees, "power": body.power}
        return await completing(robot, "rotate_degrees", args, body.wait, body.timeout)

    @app.post("/robots/{robot}/drive/set_pose", response_model=schemas.OperationState,
              responses={**_ERRORS, 202: {"model": schemas.OperationState}}, tags=["drive"],
              summary="Teleport the robot to (x, y, yaw) on the ground; completes when settled")
    async def set_pose(robot: str, body: schemas.SetPoseRequest):
        args = {"x": body.x, "y": body.y, "yaw_deg": body.yaw_deg}
        return await completing(robot, "set_pose", args, body.wait, body.timeout)

    @app.get("/robots/{robot}/drive/operations/{op_id}", response_model=schemas.OperationState,
             responses=_ERRORS, tags=["drive"], summary="A completing command's status")
    async def operation(robot: str, op_id: int):
        robot_or_404(robot)
        op = runner.operation(op_id)
        if op is None or op.robot != robot:
            raise HTTPException(404, f"no operation {op_id} on robot {robot!r}")
        return _json({**op.public(), "status_url": f"/robots/{robot}/drive/operations/{op_id}"})

    @app.post("/robots/{robot}/drive/{command}", include_in_schema=False)
    async def unknown_command(robot: str, command: str):
        robot_or_404(robot)
        ops = services_of(robot)[0]["operations"]
        if command in ("drive_distance", "rotate_degrees", "set_pose"):
            require(robot, command)
        raise HTTPException(404, f"the drive has no command {command!r}; commands: "
                            f"{', '.join(ops)}")

    # --- sensors ---
    @app.get("/robots/{robot}/encoders", response_model=schemas.EncoderState, responses=_ERRORS,
             tags=["sensors"], summary="Front-wheel encoder ticks")
    async def encoders(robot: str):
        return _json(snapshot_of(robot)["encoders"])

    @app.get("/robots/{robot}/compass", responses=_ERRORS, tags=["sensors"],
             summary="Heading (chassis yaw)")
    async def compass(robot: str):
        return _json(snapshot_of(robot)["compass"])

    @app.get("/robots/{robot}/gps", responses=_ERRORS, tags=["sensors"],
             summary="Chassis position in the world")
    async def gps(robot: str):
        return _json(snapshot_of(robot)["gps"])

    # --- webcam ---
    @app.get("/robots/{robot}/camera", responses=_ERRORS, tags=["webcam"],
             summary="Webcam description and the latest frame's URLs")
    async def camera(robot: str):
        robot_or_404(robot)
        require(robot, "camera")
        cached = camera_cache.get(robot)
        return _json({"robot": robot, "frame_png_url": f"/robots/{robot}/camera/frame.png",
                      "frame_jpeg_url": f"/robots/{robot}/camera/frame.jpg",
                      "page_url": f"/robots/{robot}/camera/page",
                      "max_rate_hz": CAMERA_MAX_RATE,
                      "latest_frame_time": None if cached is None else cached["time"]})

    async def latest_frame(robot: str) -> dict:
        """The latest frame, fetched from the sim thread at most CAMERA_MAX_RATE times per
        simulated second however many clients ask; concurrent askers share one fetch."""
        robot_or_404(robot)
        require(robot, "camera")
        cached = camera_cache.get(robot)
        if cached is not None and (runner.snapshot["time"] - cached["checked"]
                                   < 1.0 / CAMERA_MAX_RATE):
            return cached
        pending = camera_cache.get(f"{robot}/pending")
        if pending is None or pending.done():
            pending = asyncio.ensure_future(in_sim(partial(sv.grab_frame, robot)))
            camera_cache[f"{robot}/pending"] = pending
        checked, t, image = await asyncio.shield(pending)
        if image is None:
            raise HTTPException(503, f"robot {robot!r} has no camera frame yet (the first "
                                "appears one output delay after the start)")
        cached = camera_cache.get(robot)
        if cached is None or cached["time"] != t:
            cached = {"time": t, "image": _rgb(image), "encoded": {}, "checked": checked}
            camera_cache[robot] = cached
        else:
            cached["checked"] = max(cached["checked"], checked)
        return cached

    async def frame_response(robot: str, fmt: str) -> Response:
        frame = await latest_frame(robot)
        data = frame["encoded"].get(fmt)
        if data is None:
            data = await asyncio.to_thread(_encode, frame["image"], fmt)
            frame["encoded"][fmt] = data
        return Response(data, media_type=f"image/{fmt}",
                        headers={"Cache-Control": "no-store",
                                 "X-Frame-Time": f"{frame['time']:.4f}"})

    @app.get("/robots/{robot}/camera/frame.png", tags=["webcam"], responses=_ERRORS,
             response_class=Response, summary="The latest frame, PNG")
    async def frame_png(robot: str):
        return await frame_response(robot, "png")

    @app.get("/robots/{robot}/camera/frame.jpg", tags=["webcam"], responses=_ERRORS,
             response_class=Response, summary="The latest frame, JPEG")
    async def frame_jpg(robot: str):
        return await frame_response(robot, "jpeg")

    @app.get("/robots/{robot}/camera/page", response_class=HTMLResponse, tags=["webcam"],
             summary="Webcam page: the frame at a refresh interval you pick, start/stop")
    async def camera_page(robot: str,
                          interval: CameraInterval = 500):
        robot_or_404(robot)
        require(robot, "camera")
        page = (STATIC_DIR / "webcam.html").read_text()
        return HTMLResponse(page.replace("__ROBOT__", html.escape(robot))
                            .replace("__INTERVAL__", str(interval)))

    # --- subscriptions (Server-Sent Events) ---
    def extract(robot: str, service: str):
        if service == "drive":
            return lambda snap: snap["drive"]
        if service in ("encoders", "compass", "gps"):
            return lambda snap: snap[service]
        if service in runner.snapshot["robots"][robot]["ir"]:
            return lambda snap: snap["ir"][service]
        raise HTTPException(404, f"robot {robot!r} has no subscribable service {service!r}; "
                            f"services: {', '.join(_subscribable(robot))}")

    def _subscribable(robot: str) -> list[str]:
        return ["drive", *runner.snapshot["robots"][robot]["ir"], "encoders", "compass", "gps"]

    def event_stream(request: Request, robot: str, services: list[str], period: float,
                     limit: float | None):
        extractors = {s: extract(robot, s) for s in services}
        return _sse(request, robot, extractors, period, limit)

    async def _sse(request, robot, extractors, period, limit):
        last: dict[str, Any] = {}
        started = time.monotonic()
        yield "retry: 1000\n\n"
        while True:
            snap = runner.snapshot["robots"][robot]
            for name, fn in extractors.items():
                state = fn(snap)
                key = _change_key(state)
                if last.get(name) != key:
                    last[name] = key
                    yield f"event: {name}\ndata: {json.dumps(state, allow_nan=False)}\n\n"
            if limit is not None and time.monotonic() - started > limit:
                return
            if await request.is_disconnected():
                return
            await asyncio.sleep(period)

    def sse_response(generator) -> Response:
        from starlette.responses import StreamingResponse

        return StreamingResponse(generator, media_type="text/event-stream",
                                 headers={"Cache-Control": "no-store",
                                          "X-Accel-Buffering": "no"})

    @app.get("/robots/{robot}/subscribe", tags=["subscriptions"],
             summary="Server-Sent Events: one event per service whose state changed",
             response_class=Response)
    async def subscribe_all(request: Request, robot: str, services: str | None = None,
                            period: SubscribePeriod = SUBSCRIPTION_CHECK_PERIOD,
                            limit: SubscribeLimit = None):
        robot_or_404(robot)
        names = services.split(",") if services else _subscribable(robot)
        return sse_response(event_stream(request, robot, names, period, limit))

    @app.get("/robots/{robot}/{service}/subscribe", tags=["subscriptions"],
             summary="Server-Sent Events for one service (when its reading changes)",
             response_class=Response)
    async def subscribe(request: Request, robot: str, service: str,
                        period: SubscribePeriod = SUBSCRIPTION_CHECK_PERIOD,
                        limit: SubscribeLimit = None):
        robot_or_404(robot)
        return sse_response(event_stream(request, robot, [service], period, limit))

    @app.get("/robots/{robot}/{service}", responses=_ERRORS, tags=["sensors"],
             response_model=schemas.AnalogSensorState,
             summary="Analog-sensor state of an IR sensor (front_ir, rear_ir)")
    async def analog_sensor(robot: str, service: str):
        snap = snapshot_of(robot)
        if service in snap["ir"]:
            return _json(snap["ir"][service])
        raise HTTPException(404, f"robot {robot!r} has no service {service!r}; services: "
                            f"{', '.join(service_names(robot))}")

    app.mount("/static", StaticFiles(directory=STATIC_DIR), name="static")
    return app


def _change_key(state: dict) -> str:
    """A state's identity for change notification: everything but its time stamps."""
    return json.dumps({k: v for k, v in state.items() if k not in ("time", "time_stamp")},
                      sort_keys=True, default=str)


def _rgb(image):
    import numpy as np

    a = np.asarray(getattr(image, "data", image))
    if a.ndim == 3 and a.shape[2] == 4:
        a = a[:, :, :3]
    return np.ascontiguousarray(a, dtype=np.uint8)


def _encode(image, fmt: str) -> bytes:
    from PIL import Image

    buf = io.BytesIO()
    if fmt == "png":
        Image.fromarray(image).save(buf, format="PNG", compress_level=1)
    else:
        Image.fromarray(image).save(buf, format="JPEG", quality=85)
    return buf.getvalue()


def _directory_html(entries: list[dict], meshcat_url: str | None) -> str:
    rows = []
    for e in entries:
        links = [f'<a href="{html.escape(e["state_url"])}">state</a>']
        if e.get("subscribe_url"):
            links.append(f'<a href="{html.escape(e["subscribe_url"])}">subscribe</a>')
        if e.get("page_url"):
            links.append(f'<a href="{html.escape(e["page_url"])}">page</a>')
        rows.append(
            f"<tr><td>{html.escape(e['robot'])}</td><td>{html.escape(e['name'])}</td>"
            f"<td><code>{html.escape(e['contract'])}</code></td><td>{' | '.join(links)}</td>"
            f"<td>{html.escape(', '.join(e.get('operations', [])))}</td></tr>")
    meshcat = (f' | <a href="{html.escape(meshcat_url)}">Meshcat</a>' if meshcat_url else "")
    return f"""<!doctype html>
<html><head><meta charset="utf-8"><title>Service directory - corobot-drake</title>
<link rel="stylesheet" href="/static/style.css"></head>
<body><h1>Service directory</h1>
<p><a href="/dashboard">Dashboard</a> | <a href="/simulation">Simulation</a> |
<a href="/docs">API docs</a> | <a href="/openapi.json">OpenAPI</a>{meshcat}</p>
<table class="directory"><thead><tr><th>robot</th><th>service</th><th>contract</th>
<th>links</th><th>operations</th></tr></thead><tbody>
{''.join(rows)}
</tbody></table></body></html>
"""

