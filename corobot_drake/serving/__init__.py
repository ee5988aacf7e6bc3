"""The live simulation served over HTTP and driven from Meshcat.

- `runner.py`: the `Runner` protocol and `SimRunner`, the thread that owns the Context;
- `transport.py`: the same protocol across a pipe (`RemoteRunner`; the HTTP server's process);
- `calls.py`, `operations.py`, `snapshots.py`, `frames.py`: what crosses to the simulation
  thread, the commands in flight, the published state, the camera frames;
- `webapp.py`, `routes/`, `schemas.py`: the FastAPI app, its routers and its models;
- `security.py`: who may drive the robot (loopback, the bearer token, Host, JSON bodies);
- `serve.py`: `--serve` (both processes); `client.py`: `CorobotClient`; `teleop.py`: Meshcat keys;
  `view.py`: Meshcat's initial view and follow camera.
"""
