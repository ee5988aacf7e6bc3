"""`sensors.camera.CameraHold` alone: its input image fixed, its events stepped."""

import math

import numpy as np
from pydrake.systems.sensors import ImageRgba8U

from conftest import Stepper
from corobot_drake.sensors.camera import CameraHold

STEP = 0.01


def image(level: int) -> ImageRgba8U:
    frame = ImageRgba8U(4, 3)
    frame.mutable_data[:] = level
    return frame


def test_a_delayed_hold_puts_each_frame_out_a_delay_after_its_step():
    """10 Hz ticks 0.5 ms past k / 10 s on 10 ms steps, 30 ms delay: tick 0 is taken at the
    0.01 s step and comes out at the 0.04 s one; nothing before it (none at initialization);
    the frame out is the one taken, not the input now."""
    s = Stepper(CameraHold(4, 3, fps=10, capture_offset=0.0005, step=STEP, delay=0.03), STEP)
    s.fix("color_image", image(1))
    s.tick()  # 0 s
    assert s.output("rgb_image").width() == 0 and math.isnan(s.output("image_time")[0])
    s.tick()  # 0.01 s: tick 0 taken
    s.fix("color_image", image(2))
    s.tick(3)  # 0.02, 0.03, 0.04 s: out at 0.04
    assert s.output("image_time")[0] == 0.01
    assert (s.output("rgb_image").data == 1).all()
    s.tick(7)  # 0.11 s: tick 1 taken (input 2); 0.14 s: out
    assert s.output("image_time")[0] == 0.01
    s.tick(3)
    assert s.output("image_time")[0] == 0.11 and (s.output("rgb_image").data == 2).all()


def test_a_hold_without_delay_takes_a_frame_at_initialization_and_on_each_tick_s_step():
    s = Stepper(CameraHold(4, 3, fps=10, capture_offset=0.0005, step=STEP), STEP)
    s.fix("color_image", image(5))
    s.tick()
    assert s.output("image_time")[0] == 0.0 and (s.output("rgb_image").data == 5).all()
    s.fix("color_image", image(6))
    s.tick()  # 0.01 s: tick 0's step
    assert s.output("image_time")[0] == 0.01 and (s.output("rgb_image").data == 6).all()
    s.fix("color_image", image(7))
    s.tick(9)  # to 0.10 s: no tick's step yet (tick 1 is at 0.1005 s)
    assert s.output("image_time")[0] == 0.01
    assert np.array_equal(s.output("rgb_image").data, np.full((3, 4, 4), 6, np.uint8))


class FakeWorker:
    """A `RenderWorker` that "renders" a plant state as an image filled with its first
    number, and records what it was asked."""

    num_states = 2

    def __init__(self):
        self.submitted, self.taken = [], []

    def submit(self, key, state):
        self.submitted.append((key, list(state)))

    def take(self, key, state):
        self.taken.append((key, list(state)))
        return image(int(state[0]))


def test_with_a_worker_the_frame_is_rendered_from_the_plant_state_at_its_capture():
    """The capture keeps the plant's state and hands it to the worker; the frame out a delay
    later is the worker's render of that state (not of the state then), and the hold's own
    colour input is never read (left unconnected here)."""
    worker = FakeWorker()
    s = Stepper(CameraHold(4, 3, fps=10, capture_offset=0.0005, step=STEP, delay=0.03,
                           worker=worker), STEP)
    s.fix("plant_state", [3.0, 0.5])
    s.tick(2)  # 0.01 s: tick 0 taken
    s.fix("plant_state", [9.0, 0.5])
    assert [state for _, state in worker.submitted] == [[3.0, 0.5]]
    s.tick(3)  # 0.04 s: out
    assert worker.taken == []  # nothing read yet: nothing waited for
    assert s.output("image_time")[0] == 0.01 and (s.output("rgb_image").data == 3).all()
    assert worker.taken == worker.submitted  # the same key and state
    s.output("rgb_image")
    assert len(worker.taken) == 1  # read again before any update: Drake's cached frame


def test_a_render_worker_cancels_renders_nobody_took_and_renders_them_when_taken():
    """Frames submitted faster than they render: only the newest `IN_FLIGHT` wait, older
    ones not started are cancelled (never rendered), and so are those submitted before a frame
    read; taking one renders it then, the same image; the frame taken last is not rendered
    again."""
    import threading
    import time

    from corobot_drake.sensors.render_worker import IN_FLIGHT, RenderWorker

    rendered = []

    class SlowScene:
        def render(self, state):
            time.sleep(0.02)
            rendered.append(int(state[0]))
            return image(int(state[0]))

    worker = RenderWorker(SlowScene, num_states=2)
    worker.wait_ready()
    release = threading.Event()
    worker._executor.submit(release.wait)  # the thread busy until every frame is submitted
    for k in range(10):
        worker.submit(k, [k, 0.0])
    release.set()
    assert len(worker._pending) == IN_FLIGHT  # 0-5 cancelled
    assert (worker.take(9, [9, 0.0]).data == 9).all()
    assert rendered == [9]  # 6-8, submitted before the frame read, cancelled too
    assert (worker.take(2, [2, 0.0]).data == 2).all()  # cancelled: rendered when taken
    assert rendered[-1] == 2
    count = len(rendered)
    assert (worker.take(2, [2, 0.0]).data == 2).all()  # taken again: not rendered again
    assert len(rendered) == count
    release = threading.Event()
    worker._executor.submit(release.wait)
    worker.submit(10, [10, 0.0])
    worker.submit(11, [11, 0.0])
    threading.Timer(0.05, release.set).start()  # once take has run
    worker.take(11, [11, 0.0])  # a later frame read: the one before it is not rendered
    assert 10 not in rendered
    worker.close()


def test_a_render_worker_renders_ahead_only_while_a_reader_wants_frames():
    """With readers and none wanting frames (a ROS 2 image topic without a subscriber), a
    submitted frame is not rendered, and one taken anyway renders then; once a reader wants
    them, each submitted frame renders ahead again."""
    from corobot_drake.sensors.render_worker import RenderWorker

    rendered = []

    class Scene:
        def render(self, state):
            rendered.append(int(state[0]))
            return image(int(state[0]))

    worker = RenderWorker(Scene, num_states=2)
    worker.wait_ready()
    wanted = [False]
    worker.readers.append(lambda: wanted[0])
    worker.submit(1, [1, 0.0])
    assert not worker._pending
    assert (worker.take(1, [1, 0.0]).data == 1).all() and rendered == [1]  # when taken
    wanted[0] = True
    worker.submit(2, [2, 0.0])
    worker._pending[2].result()  # rendered ahead, before anyone takes it
    assert rendered == [1, 2]
    worker.close()
