"""The robot model, generated at build time from one source of numbers.

- `dimensions.py`: every dimension, mass and mount of the Corobot (the one place they live);
- `sdf.py`: the SDFormat model (`corobot_sdf`; `models/corobot.sdf` is its default output);
- `meshes.py`: the visual meshes and texture (`models/meshes/`);
- `ir_models.py`: the IR sensors' output models (ideal; the Sharp GP2D12's curve, ADC, noise).
"""
