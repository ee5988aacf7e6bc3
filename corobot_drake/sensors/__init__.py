"""The robot's sensors as Drake systems, and what they need.

- `ir_sensor.py`: `IrSensor` (the IR distance sensor, a ray cast per scan, its reading through
  an output model of `model/ir_models.py`) and its Meshcat view;
- `raycast.py`: exact ray casts against SceneGraph's shapes (Drake has none);
- `camera.py`: the cameras (Drake's RgbdSensor / RgbdSensorAsync), frame hold and saver;
- `registry.py`: each kind of sensor's `add_<kind>` (`add_ir_sensor`, `add_camera`), which the
  station finds there; `site.py`: `SensorSite`, what each is given;
- `render.py`: pictures of a scene (tools/snapshot.py); `xdisplay.py`: an X server for GL.
"""
