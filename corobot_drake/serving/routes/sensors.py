"""The odometry sensors (`/encoders`, `/compass`, `/gps`), every sensor's reading by kind and
name (`/sensors`, `/sensors/<kind>/<name>`), and the IR analog sensors, whose services are
named after the sensors (`/front_ir`, ...): `ir_router`'s path matches any service name, so
the app includes it after every other router."""

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


@router.get("/robots/{robot}/sensors", responses=schemas.ERRORS,
            summary="Every sensor's latest reading, by kind and name")
async def sensor_readings(robot: str, backend: BackendDep):
    """{kind (the scenario's map: `ir_sensors`, `cameras`, ...): {sensor name: its latest
    reading as JSON}}, every kind the simulation knows (a kind the robot lacks: {})."""
    return json_response(backend.snapshot_of(robot)["sensors"])


@router.get("/robots/{robot}/sensors/{kind}/{name}", responses=schemas.ERRORS,
            summary="One sensor's latest reading")
async def sensor_reading(robot: str, kind: str, name: str, backend: BackendDep):
    """The latest reading of the robot's sensor `name` of `kind` (its scenario map, e.g.
    `ir_sensors/rear`), as JSON with the field names of its kind's reading."""
    sensors = backend.snapshot_of(robot)["sensors"]
    reading = sensors.get(kind, {}).get(name)
    if reading is None:
        have = [f"{k}/{n}" for k, named in sensors.items() for n in named]
        raise HTTPException(404, f"robot {robot!r} has no sensor {kind}/{name}; sensors: "
                            f"{', '.join(have) or 'none'}")
    return json_response(reading)


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
