"""The robot's own LeafSystems, each one idea with named ports and its memory in the Context.

- `drive.py`: `CommandSource` (script and API inbox) and `DriveController` (power, slew, clamp);
- `motion.py`: `MotionCommands`, the DriveDistance / RotateDegrees / SetPose state machine;
- `odometry.py`: `ChassisPoses`, encoders, `Compass`, `Gps`, `DriveStateReporter`;
- `dead_reckoning.py`: `DeadReckoning`, the pose integrated from the encoders;
- `contact.py`: `WheelContacts`, each wheel's load and slip from the contact results;
- `monitor.py`: `TiltMonitor`; `runlog.py`: the run log (`RunLogSample` + a log sink).
"""
