"""The odometry sensors (`/encoders`, `/compass`, `/gps`) and the IR analog sensors, whose
services are named after the sensors (`/front_ir`, ...): `ir_router`'s path matches any
service name, so the app includes it after every other router."""

from __future__ import annotations

from fastapi import APIRouter, HTTPException

from corobot_drake.serving import schemas
from corobot_drake.serving.routes.backend import BackendDep, json_response

router = APIRouter(tags=["sensors"])
ir_router = APIRouter(tags=["sensors"])


@router.get("/robots/{robot}/encoders", response_model=schemas.EncoderState,
            responses=schemas.ERRORS, summary="Front-wheel encoder ticks")
async def encoders(robot: str, backend: BackendDep):
    return json_response(backend.snapshot_of(robot)["encoders"])


@router.get("/robots/{robot}/compass", responses=schemas.ERRORS,
            summary="Heading (chassis yaw)")
async def compass(robot: str, backend: BackendDep):
    return json_response(backend.snapshot_of(robot)["compass"])


@router.get("/robots/{robot}/gps", responses=schemas.ERRORS,
            summary="Chassis position in the world")
async def gps(robot: str, backend: BackendDep):
    return json_response(backend.snapshot_of(robot)["gps"])


@ir_router.get("/robots/{robot}/{service}", responses=schemas.ERRORS,
               response_model=schemas.AnalogSensorState,
               summary="Analog-sensor state of an IR sensor (front_ir, rear_ir)")
async def analog_sensor(robot: str, service: str, backend: BackendDep):
    snap = backend.snapshot_of(robot)
    if service in snap["ir"]:
        return json_response(snap["ir"][service])
    names = [s["name"] for s in backend.services_of(robot)]
    raise HTTPException(404, f"robot {robot!r} has no service {service!r}; services: "
                        f"{', '.join(names)}")
