"""A camera's frames rendered on a thread of its own, from a copy of the scene.

Under CENIC a capture must fall on a plant step (one between the steps would split a step and
change the motion), so Drake's `RgbdSensorAsync`, whose captures keep their own clock, is not
used there; and a render called from Python holds the GIL, so a Python thread calling the
sensor's port would stall the simulation's own Python updates. A `RenderWorker` instead
keeps a copy of the scene (the same plant, built by the station's own phase, and its scene
graph with a GL engine lit alike) and an `RgbdSensor` on the same frame, sampled by a C++
`ZeroOrderHold` inside a `Simulator` of its own: `Simulator.AdvanceTo` releases the GIL, so
the render runs on the second core while the simulation goes on. A frame is a function of the
plant's state at its capture (what the copy is set to), so it is the frame the
simulation's own sensor renders at that state, bit for bit.

The worker keeps no state a Context needs: a frame whose render was not started here (a
Context restored in memory mid-flight, e.g. by `SetTimeStateAndParametersFrom`) renders when
it is asked for.
"""

from __future__ import annotations

import collections
import concurrent.futures
import dataclasses as dc
from collections.abc import Callable

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import ZeroOrderHold
from pydrake.systems.sensors import ImageRgba8U

PERIOD = 1.0
"""s of the copy's own clock per frame: its hold samples the sensor once per advance."""
IN_FLIGHT = 4
"""Renders kept waiting to be taken (frames nobody read, or left by a Context that was
restored or reset mid-flight); an older one not yet started is cancelled."""


@dc.dataclass
class RenderScene:
    """The copy: its Simulator, its plant (state set per frame) and the hold whose
    abstract state is the latest frame."""

    simulator: Simulator
    plant: object
    hold: ZeroOrderHold

    def render(self, state: np.ndarray) -> ImageRgba8U:
        """The frame at the plant state `state` ([q; v]: only q shows)."""
        context = self.simulator.get_mutable_context()
        self.plant.SetPositionsAndVelocities(self.plant.GetMyMutableContextFromRoot(context),
                                             state)
        # One hold sample, half a period in (the copy's clock stands half a period off the
        # hold's events), of the state as set: the plant's own update never comes.
        self.simulator.AdvanceTo(context.get_time() + PERIOD)
        held = self.hold.GetMyContextFromRoot(context).get_abstract_state(0).get_value()
        image = ImageRgba8U(held.width(), held.height())
        image.mutable_data[:] = held.data  # a copy: the hold's is overwritten next frame
        return image


def build_render_scene(add_scene_and_sensor: Callable, width: int, height: int) -> RenderScene:
    """The copy: `add_scene_and_sensor(builder)` adds the plant, its scene graph and the
    camera's `RgbdSensor`, and returns (plant, the sensor's colour image port)."""
    builder = DiagramBuilder()
    plant, image = add_scene_and_sensor(builder)
    hold = builder.AddSystem(ZeroOrderHold(PERIOD, AbstractValue.Make(ImageRgba8U(width,
                                                                                  height))))
    builder.Connect(image, hold.get_input_port())
    simulator = Simulator(builder.Build())
    context = simulator.get_mutable_context()
    context.SetTime(PERIOD / 2)
    simulator.Initialize()
    scene = RenderScene(simulator, plant, hold)
    # A first frame now: a GL that fails only when it draws fails here, where the camera can
    # still render in place instead, and the shaders are compiled before the first capture.
    scene.render(plant.GetPositionsAndVelocities(plant.GetMyContextFromRoot(context)))
    return scene


class RenderWorker:
    """Renders frames on one thread of its own (`concurrent.futures`), the copy of the scene
    made there by `make_scene()` (a `RenderScene`) as soon as the worker starts (`wait_ready`
    waits for it). `submit` a frame's key and state at its capture, `take` its image when it
    is read."""

    def __init__(self, make_scene: Callable[[], RenderScene], num_states: int):
        self.num_states = num_states
        """The size of the plant state ([q; v]) a frame is rendered from."""
        self._executor = concurrent.futures.ThreadPoolExecutor(
            max_workers=1, thread_name_prefix="corobot-camera")
        self._scene = self._executor.submit(make_scene)
        self._pending: collections.OrderedDict = collections.OrderedDict()
        """Renders started, by frame key, oldest first; touched only by the thread that
        advances and reads the simulation (`submit` and `take`; a Simulation is used from one
        thread at a time), so no lock."""
        self._taken: tuple = (None, None)
        """(key, image) of the frame taken last: read again (Drake's cache of the output that
        reads it is cleared by the hold's next update) it is not rendered again."""
        self.renders = 0
        """Frames rendered so far (on the worker's thread)."""
        self.readers: list[Callable[[], bool]] = []
        """Who reads every frame, each saying whether it wants frames now (a ROS 2 topic:
        while it has a subscriber). With readers and none wanting, `submit` renders nothing
        ahead (a frame read anyway, `take`, renders then); with none, every frame is."""

    def wait_ready(self) -> None:
        """Waits until the copy is built (raising what building it raised)."""
        self._scene.result()

    def _render(self, state: np.ndarray) -> ImageRgba8U:
        self.renders += 1
        return self._scene.result().render(state)

    def submit(self, key, state) -> None:
        """Starts rendering the frame `key` (hashable: its capture) at the plant's
        `state`, unless its `readers` want none now."""
        if self.readers and not any(wanted() for wanted in self.readers):
            return
        self._pending[key] = self._executor.submit(self._render, np.array(state, dtype=float))
        while len(self._pending) > IN_FLIGHT:
            self._pending.popitem(last=False)[1].cancel()  # nobody took it: render no more

    def take(self, key, state) -> ImageRgba8U:
        """The frame `key`: the render `submit` started (waiting for it), or, when none was
        started here (or it was cancelled), one made now from `state`. Renders submitted
        before it and not started are cancelled: frames are read in order."""
        if key == self._taken[0]:
            return self._taken[1]
        if key in self._pending:
            for older in list(self._pending):
                if older == key:
                    break
                self._pending.pop(older).cancel()
        future = self._pending.pop(key, None)
        if future is None or future.cancelled():
            future = self._executor.submit(self._render, np.array(state, dtype=float))
        self._taken = (key, future.result())
        return self._taken[1]

    def close(self) -> None:
        """Drops the copy on the worker's thread (its GL engine is torn down there, not
        beside another thread's GL calls) and ends the thread, waiting for both. Idempotent."""
        try:
            self._executor.submit(self._drop)
        except RuntimeError:  # closed, or the interpreter is exiting and has joined it
            return
        self._executor.shutdown(wait=True)

    def _drop(self) -> None:
        self._scene = None  # the copy's last reference: it is freed here, on this thread
