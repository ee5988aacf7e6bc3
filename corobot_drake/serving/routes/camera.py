"""The webcam contract, per camera: its description, the latest frame as PNG or JPEG, and the
webcam page; at `/robots/<robot>/cameras/<camera>/...` for every camera of the robot, and at
`/robots/<robot>/camera/...` for its front camera (`backend.camera_path`)."""

from __future__ import annotations

import html
import json
from functools import partial
from typing import Annotated

from fastapi import APIRouter, HTTPException, Query
from fastapi.responses import HTMLResponse, Response

from corobot_drake.config.sensors import FRONT_CAMERA
from corobot_drake.serving import calls, schemas
from corobot_drake.serving.frames import CAMERA_MAX_RATE
from corobot_drake.serving.routes.backend import (
    STATIC_DIR,
    Backend,
    BackendDep,
    camera_path,
    json_response,
)
from corobot_drake.serving.snapshots import jsonable

router = APIRouter(tags=["webcam"])

CameraInterval = Annotated[int, Query(ge=20, le=60000, description="refresh interval, ms")]


async def describe(backend: Backend, robot: str, camera: str) -> Response:
    """The camera's description: its frames' and page's URLs, the time of the latest frame
    the camera has rendered (asked of the simulation: fetched or not; null before the first,
    or the last one fetched once the simulation has stopped)."""
    backend.camera(robot, camera)
    base = f"/robots/{robot}/{camera_path(camera)}"
    try:
        latest = await backend.in_sim(partial(calls.frame_time, robot, camera=camera))
    except HTTPException:  # the simulation is not running
        latest = backend.frames.latest_time(f"{robot}/{camera}")
    return json_response({"robot": robot, "camera": camera,
                          "frame_png_url": f"{base}/frame.png",
                          "frame_jpeg_url": f"{base}/frame.jpg", "page_url": f"{base}/page",
                          "max_rate_hz": CAMERA_MAX_RATE,
                          "latest_frame_time": jsonable(latest)})


async def frame_response(backend: Backend, robot: str, camera: str, fmt: str) -> Response:
    """The camera's latest frame as `fmt` (png or jpeg); 503 before the first."""
    backend.camera(robot, camera)
    frame = await backend.frames.latest(
        f"{robot}/{camera}", backend.runner.snapshot["time"],
        partial(backend.in_sim, partial(calls.grab_frame, robot, camera=camera)))
    if frame is None:
        raise HTTPException(503, f"robot {robot!r} has no frame of camera {camera!r} yet (the "
                            "first appears one output delay after the start)")
    data = await backend.frames.encoded(frame, fmt)
    return Response(data, media_type=f"image/{fmt}",
                    headers={"Cache-Control": "no-store", "X-Frame-Time": f"{frame.time:.4f}"})


def page(backend: Backend, robot: str, camera: str, interval: int) -> HTMLResponse:
    """The camera's webcam page, refreshing every `interval` ms."""
    backend.camera(robot, camera)
    frame_url = f"/robots/{robot}/{camera_path(camera)}/frame.png"
    text = (STATIC_DIR / "webcam.html").read_text()
    return HTMLResponse(text.replace("__ROBOT__", html.escape(robot))
                        .replace("__CAMERA__", html.escape(camera))
                        .replace("__FRAME_URL__", json.dumps(frame_url))
                        .replace("__INTERVAL__", str(interval)))


@router.get("/robots/{robot}/camera", responses=schemas.ERRORS,
            summary="The front camera: its description and the latest frame's URLs")
async def camera(robot: str, backend: BackendDep):
    return await describe(backend, robot, FRONT_CAMERA)


@router.get("/robots/{robot}/camera/frame.png", responses=schemas.ERRORS,
            response_class=Response, summary="The front camera's latest frame, PNG")
async def frame_png(robot: str, backend: BackendDep):
    return await frame_response(backend, robot, FRONT_CAMERA, "png")


@router.get("/robots/{robot}/camera/frame.jpg", responses=schemas.ERRORS,
            response_class=Response, summary="The front camera's latest frame, JPEG")
async def frame_jpg(robot: str, backend: BackendDep):
    return await frame_response(backend, robot, FRONT_CAMERA, "jpeg")


@router.get("/robots/{robot}/camera/page", response_class=HTMLResponse,
            summary="The front camera's webcam page: the frame at a refresh interval you "
                    "pick, start/stop")
async def camera_page(robot: str, backend: BackendDep, interval: CameraInterval = 500):
    return page(backend, robot, FRONT_CAMERA, interval)


@router.get("/robots/{robot}/cameras/{camera}", responses=schemas.ERRORS,
            summary="A camera: its description and the latest frame's URLs")
async def named_camera(robot: str, camera: str, backend: BackendDep):
    return await describe(backend, robot, camera)


@router.get("/robots/{robot}/cameras/{camera}/frame.png", responses=schemas.ERRORS,
            response_class=Response, summary="A camera's latest frame, PNG")
async def named_frame_png(robot: str, camera: str, backend: BackendDep):
    return await frame_response(backend, robot, camera, "png")


@router.get("/robots/{robot}/cameras/{camera}/frame.jpg", responses=schemas.ERRORS,
            response_class=Response, summary="A camera's latest frame, JPEG")
async def named_frame_jpg(robot: str, camera: str, backend: BackendDep):
    return await frame_response(backend, robot, camera, "jpeg")


@router.get("/robots/{robot}/cameras/{camera}/page", response_class=HTMLResponse,
            summary="A camera's webcam page")
async def named_camera_page(robot: str, camera: str, backend: BackendDep,
                            interval: CameraInterval = 500):
    return page(backend, robot, camera, interval)
