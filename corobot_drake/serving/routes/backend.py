"""What every router needs: the app's `Backend` (its runner, robots, operations and frame
cache, as a FastAPI dependency), the service catalogue, and JSON answers.

Used from the HTTP event loop's thread only; the runner is the one thing shared with others.
"""

from __future__ import annotations

import asyncio
import json
from pathlib import Path
from typing import Annotated, Any

from fastapi import Depends, HTTPException, Request
from fastapi.responses import Response

from corobot_drake import commands
from corobot_drake.config.sensors import FRONT_CAMERA
from corobot_drake.names import unknown_robot
from corobot_drake.serving.frames import FrameCache
from corobot_drake.serving.operations import Operations
from corobot_drake.serving.runner import Runner, SimulationStoppedError
from corobot_drake.serving.snapshots import RobotInfo

STATIC_DIR = Path(__file__).resolve().parent.parent / "static"

CONTRACT_DRIVE = "corobot-drake/drive/v1"
CONTRACT_ANALOG_SENSOR = "corobot-drake/analog_sensor/v1"
CONTRACT_ENCODERS = "corobot-drake/encoders/v1"
CONTRACT_COMPASS = "corobot-drake/compass/v1"
CONTRACT_GPS = "corobot-drake/gps/v1"
CONTRACT_WEBCAM = "corobot-drake/webcam/v1"

DRIVE_OPERATIONS = list(commands.BY_METHOD)
"""The drive service's commands, as the directory lists them (`commands.py`)."""


def json_response(content: Any, status_code: int = 200,
                  headers: dict[str, str] | None = None) -> Response:
    """`content` as JSON (no NaN or Infinity: `snapshots.jsonable` made them null)."""
    return Response(json.dumps(content, allow_nan=False), status_code=status_code,
                    media_type="application/json", headers=headers)


class Backend:
    """The routes' view of a started runner, plus the app's own memory: the operations
    started over HTTP and the camera's latest frames. The robots are the runner's as they
    are now (a robot spawned or deleted while serving comes or goes)."""

    def __init__(self, runner: Runner):
        if not runner.robots:
            raise ValueError("start the runner before creating its app")
        self.runner = runner
        self.operations = Operations()
        self.frames = FrameCache()

    @property
    def robot_names(self) -> list[str]:
        return list(self.runner.robots)

    def robot(self, name: str) -> RobotInfo:
        """The named robot's info; 404 naming the robots if there is none."""
        info = self.runner.robots.get(name)
        if info is None:
            raise HTTPException(404, unknown_robot(name, self.robot_names))
        return info

    def snapshot_of(self, robot: str) -> dict:
        """The robot's latest published state (404 for an unknown robot, and for one the
        runner's robots and its snapshot do not both hold yet: spawned or deleted just now)."""
        self.robot(robot)
        states = self.runner.snapshot["robots"]
        if robot not in states:
            raise HTTPException(404, unknown_robot(robot, states))
        return states[robot]

    def camera(self, robot: str, camera: str = FRONT_CAMERA) -> RobotInfo:
        """The robot's info; 404 for an unknown robot, 501 if it lacks its front camera (the
        `/camera` routes'), 404 naming its cameras if it lacks another."""
        info = self.robot(robot)
        if camera not in info.cameras:
            if camera == FRONT_CAMERA:
                raise HTTPException(501, "camera is not available in this build of the "
                                    "simulation")
            raise HTTPException(404, f"robot {robot!r} has no camera {camera!r}; cameras: "
                                f"{', '.join(info.cameras) or 'none'}")
        return info

    async def in_sim(self, fn, timeout: float = 10.0):
        """`fn(sim)`'s result, called in the simulation thread: 503 if the simulation is not
        running or does not answer within `timeout` s; 422 for the bad values it rejects."""
        if not self.runner.alive:
            raise HTTPException(503, "the simulation is not running")
        future = self.runner.submit(fn)
        try:
            return await asyncio.wait_for(asyncio.wrap_future(future), timeout)
        except TimeoutError:
            raise HTTPException(503, "the simulation did not answer in time") from None
        except SimulationStoppedError as e:  # it stopped while the request waited
            raise HTTPException(503, str(e)) from None
        except (ValueError, KeyError, TypeError) as e:
            raise HTTPException(422, str(e).strip("'\"")) from None

    def services_of(self, robot: str) -> list[dict]:
        """The robot's entries in the service directory (`schemas.ServiceEntry`)."""
        info = self.robot(robot)
        base = f"/robots/{robot}"

        def entry(name: str, contract: str, subscribe: bool = True, **extra) -> dict:
            return dict(robot=robot, name=name, contract=contract,
                        state_url=f"{base}/{name}",
                        **({"subscribe_url": f"{base}/{name}/subscribe"} if subscribe else {}),
                        **extra)

        out = [entry("drive", CONTRACT_DRIVE, operations=list(DRIVE_OPERATIONS))]
        out += [entry(name, CONTRACT_ANALOG_SENSOR) for name in info.ir_services]
        out += [entry("encoders", CONTRACT_ENCODERS), entry("compass", CONTRACT_COMPASS),
                entry("gps", CONTRACT_GPS)]
        for camera in info.cameras:
            path = camera_path(camera)
            out.append(entry(path, CONTRACT_WEBCAM, subscribe=False,
                             page_url=f"{base}/{path}/page",
                             operations=["frame.png", "frame.jpg"]))
        return out

    def subscribable(self, robot: str) -> list[str]:
        """The services a robot's subscription can send, in the directory's order."""
        return ["drive", *self.robot(robot).ir_services, "encoders", "compass", "gps"]


def camera_path(camera: str) -> str:
    """A camera's routes under `/robots/<robot>/`: `camera` for the front camera (also at
    `cameras/front`), `cameras/<camera>` for another."""
    return "camera" if camera == FRONT_CAMERA else f"cameras/{camera}"


def get_backend(request: Request) -> Backend:
    return request.app.state.backend


BackendDep = Annotated[Backend, Depends(get_backend)]
"""A route parameter that receives the app's `Backend`."""
