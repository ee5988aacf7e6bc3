"""The webcam contract: `/camera` (its description), the latest frame as PNG or JPEG, and the
webcam page."""

from __future__ import annotations

import html
from functools import partial
from typing import Annotated

from fastapi import APIRouter, HTTPException, Query
from fastapi.responses import HTMLResponse, Response

from corobot_drake.serving import calls, schemas
from corobot_drake.serving.frames import CAMERA_MAX_RATE
from corobot_drake.serving.routes.backend import STATIC_DIR, Backend, BackendDep, json_response

router = APIRouter(tags=["webcam"])

CameraInterval = Annotated[int, Query(ge=20, le=60000, description="refresh interval, ms")]


@router.get("/robots/{robot}/camera", responses=schemas.ERRORS,
            summary="Webcam description and the latest frame's URLs")
async def camera(robot: str, backend: BackendDep):
    backend.camera(robot)
    return json_response({"robot": robot, "frame_png_url": f"/robots/{robot}/camera/frame.png",
                          "frame_jpeg_url": f"/robots/{robot}/camera/frame.jpg",
                          "page_url": f"/robots/{robot}/camera/page",
                          "max_rate_hz": CAMERA_MAX_RATE,
                          "latest_frame_time": backend.frames.latest_time(robot)})


async def frame_response(backend: Backend, robot: str, fmt: str) -> Response:
    """The robot's latest frame as `fmt` (png or jpeg); 503 before the first."""
    backend.camera(robot)
    frame = await backend.frames.latest(robot, backend.runner.snapshot["time"],
                                        partial(backend.in_sim, partial(calls.grab_frame, robot)))
    if frame is None:
        raise HTTPException(503, f"robot {robot!r} has no camera frame yet (the first "
                            "appears one output delay after the start)")
    data = await backend.frames.encoded(frame, fmt)
    return Response(data, media_type=f"image/{fmt}",
                    headers={"Cache-Control": "no-store", "X-Frame-Time": f"{frame.time:.4f}"})


@router.get("/robots/{robot}/camera/frame.png", responses=schemas.ERRORS,
            response_class=Response, summary="The latest frame, PNG")
async def frame_png(robot: str, backend: BackendDep):
    return await frame_response(backend, robot, "png")


@router.get("/robots/{robot}/camera/frame.jpg", responses=schemas.ERRORS,
            response_class=Response, summary="The latest frame, JPEG")
async def frame_jpg(robot: str, backend: BackendDep):
    return await frame_response(backend, robot, "jpeg")


@router.get("/robots/{robot}/camera/page", response_class=HTMLResponse,
            summary="Webcam page: the frame at a refresh interval you pick, start/stop")
async def camera_page(robot: str, backend: BackendDep, interval: CameraInterval = 500):
    backend.camera(robot)
    page = (STATIC_DIR / "webcam.html").read_text()
    return HTMLResponse(page.replace("__ROBOT__", html.escape(robot))
                        .replace("__INTERVAL__", str(interval)))
