"""The robot's own LeafSystems, each one idea with named ports and its memory in the Context.

- `drive.py`: `CommandSource` (script and API inbox) and `DriveController` (power, slew, clamp);
- `motion.py`: `MotionCommands`, the DriveDistance / RotateDegrees / SetPose state machine;
- `odometry.py`: `ChassisPoses`, encoders, `Compass`, `Gps`, `DriveStateReporter`;
- `dead_reckoning.py`: `DeadReckoning`, the pose integrated from the encoders;
- `contact.py`: `WheelContacts`, each wheel's load (from the contact results), slip ratio
  and slip angle;
- `stability.py`: `TipMargin`, the tip-over margin and its least over the run;
- `slip_markers.py`: `SlipMarkers`, each wheel's slip as a coloured ball in Meshcat;
- `monitor.py`: `TiltMonitor`; `runlog.py`: the run log (`RunLogSample` + a log sink).
"""
