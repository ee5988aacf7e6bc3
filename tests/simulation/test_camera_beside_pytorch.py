"""A camera's frame, then PyTorch's compiler in the same process (as a Stable-Baselines3 PPO
builds its optimizer after a GoToGoal env with a camera has rendered): Mesa's LLVM and triton's
stay apart (`camera.load_triton_before_mesa`). Without it the process dies of a segfault in
triton's static initializers; run in a child process so that would fail the test, not the
suite."""

import importlib.util
import subprocess
import sys

import pytest

from conftest import REPO

CHILD = """
from corobot_drake.resources import SCENARIOS_DIR
from corobot_drake.simulation import Simulation

sim = Simulation.from_file(SCENARIOS_DIR / "camera_view.yaml")
sim.advance(0.1)
assert sim.robot().camera_image().shape == (240, 320, 4)
import triton  # what torch.optim's first use imports
print("both loaded")
"""


@pytest.mark.skipif(importlib.util.find_spec("triton") is None,
                    reason="PyTorch's triton is not installed (the [train] extra)")
def test_a_camera_frame_then_triton_in_one_process():
    done = subprocess.run([sys.executable, "-c", CHILD], capture_output=True, text=True,
                          timeout=300, cwd=REPO)
    assert done.returncode == 0, f"exit {done.returncode}\n{done.stderr[-2000:]}"
    assert done.stdout.strip().endswith("both loaded")
