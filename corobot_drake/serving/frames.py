"""The webcams' frames on the HTTP side: each camera's latest frame, fetched from the simulation
at most `CAMERA_MAX_RATE` times per simulated second however many clients ask, and encoded
once per format. Used from the HTTP event loop's thread only (encoding runs in a worker).
"""

from __future__ import annotations

import asyncio
import dataclasses as dc
import io
from collections.abc import Awaitable, Callable
from typing import Any

CAMERA_MAX_RATE = 15.0
"""Hz: frames are fetched on request, at most this often (simulated time)."""

FrameGrab = tuple[float, float, Any]
"""(simulated time, frame time, RGB image or None): what `calls.grab_frame` returns."""


@dc.dataclass
class Frame:
    time: float
    """Simulated time the frame was captured."""
    image: Any
    """RGB uint8, height x width x 3."""
    checked: float
    """Simulated time it was last found to be the latest."""
    encoded: dict[str, bytes] = dc.field(default_factory=dict)


class FrameCache:
    """The latest frame of each camera, by key (`<robot>/<camera>`; see the module
    docstring)."""

    def __init__(self, max_rate: float = CAMERA_MAX_RATE):
        self.max_rate = max_rate
        self._frames: dict[str, Frame] = {}
        self._fetches: dict[str, asyncio.Future] = {}

    def latest_time(self, camera: str) -> float | None:
        """The time of the camera's latest frame fetched so far (None: none yet)."""
        frame = self._frames.get(camera)
        return None if frame is None else frame.time

    async def latest(self, camera: str, now: float,
                     fetch: Callable[[], Awaitable[FrameGrab]]) -> Frame | None:
        """The camera's latest frame as of simulated time `now`: the cached one if it was
        checked less than 1 / max_rate s ago, else what `fetch()` brings (concurrent askers
        share one fetch). None before the camera's first frame."""
        frame = self._frames.get(camera)
        if frame is not None and now - frame.checked < 1.0 / self.max_rate:
            return frame
        pending = self._fetches.get(camera)
        if pending is None or pending.done():
            pending = self._fetches[camera] = asyncio.ensure_future(fetch())
        checked, t, image = await asyncio.shield(pending)
        if image is None:
            return None
        frame = self._frames.get(camera)
        if frame is None or frame.time != t:
            frame = self._frames[camera] = Frame(t, image, checked)
        else:
            frame.checked = max(frame.checked, checked)
        return frame

    @staticmethod
    async def encoded(frame: Frame, fmt: str) -> bytes:
        """The frame as `png` or `jpeg` bytes (encoded once per format)."""
        data = frame.encoded.get(fmt)
        if data is None:
            data = frame.encoded[fmt] = await asyncio.to_thread(_encode, frame.image, fmt)
        return data


def _encode(image, fmt: str) -> bytes:
    from PIL import Image

    buf = io.BytesIO()
    if fmt == "png":
        Image.fromarray(image).save(buf, format="PNG", compress_level=1)
    else:
        Image.fromarray(image).save(buf, format="JPEG", quality=85)
    return buf.getvalue()
