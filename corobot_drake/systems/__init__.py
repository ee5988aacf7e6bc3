"""The robot's own LeafSystems, each one idea with named ports and its memory in the Context.

- `drive.py`: `CommandSource` (script and API inbox) and `DriveController` (power, slew, clamp);
- `motion.py`: `MotionCommands`, the DriveDistance / RotateDegrees / SetPose state machine;
- `odometry.py`: `ChassisPoses`, the chassis states (a C++ gain on the plant's state),
  encoders, `Compass`, `Gps`, `DriveStateReporter`;
- `dead_reckoning.py`: `DeadReckoning`, the pose integrated from the encoders (their samples
  held by a C++ shift register, folded by `PoseIntegrator`);
- `contact.py`: `WheelContacts`, each wheel's load (from the contact results), slip ratio
  and slip angle;
- `stability.py`: `TipMargin`, the tip-over margin and its least over the run;
- `slip_markers.py`: `SlipMarkers`, each wheel's slip as a coloured ball in Meshcat;
- `runlog.py`: the run log (a log sink of C++ signals, its columns and the run's largest tilt
  made when read);
- `servo.py`: the probe of CENIC's PD sign defect and its compensation (`add_servo_sign`).
"""
