"""The Python `Robot`'s parts (`simulation.Robot` is its core and composes them): one module
a part, each a mixin reading the robot's Simulation (`_sim`), station parts (`_parts`) and
`spec` (`robots.RobotSpec`):

- `commands.py`: issuing commands and waiting for them (`CommandHandle`), the command log;
- `drive.py`: the pose, velocity, wheels, encoders and odometry;
- `telemetry.py`: the signals, contact telemetry, tip margin, run log and summary;
- `sensors.py`: every kind's sensors by name, and the IR sensors' and cameras' accessors.
"""
