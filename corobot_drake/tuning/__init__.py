"""System identification and calibration: fit the drive model to a run log (`sysid`), tune
MotorTorqueScaling and the drive by simulation (`drive_tuning`), pick the motors' effort limit
from the tire-grip sweep (`tire_grip`) and calibrate the odometry (`odometry_calibration`).
docs/tuning.md shows each at work; `tools/` has a command line for each."""
