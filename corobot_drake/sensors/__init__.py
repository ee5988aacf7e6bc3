"""The robot's sensors as Drake systems, and what they need.

- `ir_sensor.py`: `IrSensor` (the IR distance sensor, a ray cast per scan, its reading through
  an output model of `model/ir_models.py`) and its Meshcat view;
- `raycast.py`: exact ray casts against SceneGraph's shapes (Drake has none);
- `camera.py`: the cameras (Drake's RgbdSensor / RgbdSensorAsync), frame hold and saver;
- `kind.py`: `SensorKind`, what a kind of sensor declares once for every front end, and
  `BuiltSensor`, one sensor as built; `registry.py`: `KINDS`, the registered kinds (each
  module's `SensorKind`: `IrSensorKind`, `CameraKind`), which the station and front ends loop
  over; `site.py`: `SensorSite`, what each is given;
- `render.py`: pictures of a scene (tools/snapshot.py); `xdisplay.py`: an X server for GL.
"""
