"""A camera's frame, then PyTorch's optimizers in the same process (as Stable-Baselines3's PPO
builds them after a GoToGoal env with a camera has rendered): Mesa's LLVM and triton's stay
apart (`camera.load_triton_apart`), even when Mesa came into the process before the
simulation's camera (another GL user made a context first). Without it the process dies of a
segfault in triton's static initializers (exit -11, either order); the case runs in a child
process so that would fail the test, not the suite."""

import importlib.util
import subprocess
import sys

import pytest

from conftest import REPO

MESA_FIRST = """
from pydrake.geometry import MakeRenderEngineGl, RenderEngineGlParams
from corobot_drake.sensors.xdisplay import x_display
assert x_display() is not None
other_gl_user = MakeRenderEngineGl(RenderEngineGlParams())
"""
CAMERA_THEN_TORCH = """
from corobot_drake.resources import SCENARIOS_DIR
from corobot_drake.simulation import Simulation

sim = Simulation.from_file(SCENARIOS_DIR / "camera_view.yaml")
sim.advance(0.1)
assert sim.robot().camera_image().shape == (240, 320, 4)
import torch
torch.optim.Adam(torch.nn.Linear(3, 2).parameters())  # imports triton
print("both loaded")
"""


@pytest.mark.skipif(importlib.util.find_spec("triton") is None,
                    reason="PyTorch's triton is not installed (the [train] extra)")
def test_a_camera_frame_then_pytorch_in_one_process_with_mesa_there_first():
    """The harder order (a plain triton import after the camera would crash too): it also
    fails if the camera does not import triton at all, as torch would import it after Mesa."""
    done = subprocess.run([sys.executable, "-c", MESA_FIRST + CAMERA_THEN_TORCH],
                          capture_output=True, text=True, timeout=300, cwd=REPO)
    assert done.returncode == 0, f"exit {done.returncode}\n{done.stderr[-2000:]}"
    assert done.stdout.strip().endswith("both loaded")
