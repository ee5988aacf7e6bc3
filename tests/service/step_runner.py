"""`StepRunner`: the HTTP routes over a simulation the test advances itself (test_tables.py,
signal_added.py)."""

import concurrent.futures

from corobot_drake.serving import snapshots


class StepRunner:
    """The `serving.runner.Runner` the routes use, over a simulation the test advances itself:
    a submitted call runs at once, at the simulation's current time (as `SimRunner` runs it
    between steps), so an HTTP command is issued at a time the test knows."""

    def __init__(self, sim):
        self.sim = sim
        self.robots = {n: snapshots.RobotInfo.of(r) for n, r in sim.robots.items()}
        self.alive, self.meshcat_url = True, None

    @property
    def snapshot(self) -> dict:
        return snapshots.snapshot(self.sim)

    def submit(self, fn):
        future = concurrent.futures.Future()
        try:
            future.set_result(fn(self.sim))
        except Exception as e:  # the routes answer it (422, ...)
            future.set_exception(e)
        return future

    def watch(self, fn):
        return self.submit(fn)

    def stats(self) -> dict:
        return {"time": self.sim.time}
