"""The robot model, generated at build time from one source of numbers.

- `dimensions.py`: the Corobot's CAD: every dimension, mass and mount its model is made of
  (read by model generation only; the simulator reads the model and the robot file);
- `sdf.py`: the SDFormat model (`corobot_sdf`; `models/corobot.sdf` is its default output);
- `robot_file.py`: the robot file's CAD figures (wheels, sensor mounts) kept in step;
- `meshes.py`: the visual meshes and texture (`models/meshes/`);
- `ir_models.py`: the IR sensors' output models (ideal; the Sharp GP2D12's curve, ADC, noise).
"""
