"""`python -m corobot_drake.ros2.build`: builds the ROS 2 interface packages that no wheel
ships (tf2_msgs, simulation_interfaces, corobot_interfaces; `ros_packages/`) into this
virtual environment.

Plain CMake + Ninja with the `[ros2]` extra's ament_cmake and rosidl generators, no colcon.
Two snags of the wheels are dealt with first: their exported CMake files name the builder's
own Python (`/opt/python/cp3XX-cp3XX/...`), rewritten here to this environment's; and a few
ament_cmake helpers that the configure step asks for are missing from their dependencies (the
`[ros2]` extra lists them). A package built from unchanged sources is skipped (a stamp of its
files' hash beside its installed share/ directory), so running it again is quick.

Exit status: 0 built or up to date; 2 when something it needs is missing (one line names it).

It imports nothing of the simulator: a ROS 2 user's environment of ROS 2's wheels alone
(tools/ros2_user_requirements.txt) runs it from the clone's root, `python -m
corobot_drake.ros2.build`, and gets the same packages (docs/ros2.md).
"""

from __future__ import annotations

import hashlib
import os
import re
import shutil
import subprocess
import sys
import sysconfig
import tempfile
from pathlib import Path

from corobot_drake.extras import install_hint

INTERFACES_DIR = Path(__file__).resolve().parent / "ros_packages"
PACKAGES = ("tf2_msgs", "simulation_interfaces", "corobot_interfaces")
"""Built in this order (none depends on another)."""
STAMP = "corobot_drake_build.stamp"
"""Beside a built package's share/<package>/package.xml: the hash of what it was built from."""

BUILDER_PYTHON = re.compile(r"/opt/python/cp3\d+-cp3\d+t?")
"""The wheels' builder's Python prefix, as their exported CMake files name it."""


class BuildError(Exception):
    """What is missing or failed, in one line."""


def prefix() -> Path:
    """The environment the packages go into: this virtual environment."""
    if sys.prefix == sys.base_prefix:
        raise BuildError("run it with a virtual environment's Python (tools/setup makes "
                         ".venv): it installs into the environment")
    return Path(sys.prefix)


def _fixed_cmake_text(text: str) -> str:
    """`text` with the builder's Python paths made this environment's: its headers, numpy's
    headers, and its prefix."""
    import numpy

    version = f"python{sys.version_info.major}.{sys.version_info.minor}"
    text = re.sub(BUILDER_PYTHON.pattern + rf"/include/{version}",
                  sysconfig.get_paths()["include"], text)
    text = re.sub(BUILDER_PYTHON.pattern + rf"/lib/{version}/site-packages/numpy/_core/include",
                  numpy.get_include(), text)
    return BUILDER_PYTHON.sub(str(prefix()), text)


def fix_exported_cmake(root: Path) -> int:
    """Rewrites the builder's Python paths in the wheels' CMake files under `root`/share;
    returns how many files changed (0 the second time)."""
    changed = 0
    for path in (root / "share").glob("*/cmake/*.cmake"):
        text = path.read_text()
        if BUILDER_PYTHON.search(text):
            path.write_text(_fixed_cmake_text(text))
            changed += 1
    return changed


def source_hash(package: Path) -> str:
    """The hash of a package's sources (every file's path and bytes) and this Python."""
    digest = hashlib.sha256(sys.version.encode())
    for path in sorted(p for p in package.rglob("*") if p.is_file()):
        digest.update(str(path.relative_to(package)).encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()


def _stamp(root: Path, name: str) -> Path:
    return root / "share" / name / STAMP


def up_to_date(root: Path, name: str) -> bool:
    stamp = _stamp(root, name)
    return stamp.is_file() and stamp.read_text() == source_hash(INTERFACES_DIR / name)


def _tools() -> dict:
    tools = {name: shutil.which(name) for name in ("cmake", "ninja")}
    missing = [name for name, path in tools.items() if path is None]
    if missing:
        raise BuildError(f"{' and '.join(missing)} not found: install them (apt-get install "
                         f"{' '.join('ninja-build' if m == 'ninja' else m for m in missing)})")
    return tools


def build_package(root: Path, name: str, quiet: bool = True) -> None:
    """Configures, builds and installs interface package `name` into `root`."""
    tools = _tools()
    env = dict(os.environ, AMENT_PREFIX_PATH=str(root), CMAKE_PREFIX_PATH=str(root))
    with tempfile.TemporaryDirectory(prefix=f"corobot-{name}-") as build:
        steps = (
            [tools["cmake"], "-G", "Ninja", "-S", str(INTERFACES_DIR / name), "-B", build,
             f"-DCMAKE_MAKE_PROGRAM={tools['ninja']}", f"-DCMAKE_INSTALL_PREFIX={root}",
             f"-DPython3_EXECUTABLE={sys.executable}", "-DBUILD_TESTING=OFF",
             "-DCMAKE_BUILD_TYPE=Release"],
            [tools["cmake"], "--build", build, "--target", "install"],
        )
        for step in steps:
            status, output = run_step(step, env, quiet, name)
            if status != 0:
                raise BuildError(f"{name}: {Path(step[0]).name} failed:\n{_last_lines(output)}")
    _stamp(root, name).write_text(source_hash(INTERFACES_DIR / name))


NINJA_PROGRESS = re.compile(r"\[(\d+)/(\d+)\]")
"""Ninja's `[done/total]` at the start of each line it prints (on a pipe, one per step)."""


def run_step(command: list[str], env: dict, quiet: bool, name: str) -> tuple[int, str]:
    """Runs one step of a package's build: (its status, its output). Quiet, the output is
    kept, and Ninja's progress becomes one line each quarter (a package of many interfaces
    builds for minutes); otherwise it is shown as it comes."""
    if not quiet:
        return subprocess.run(command, env=env).returncode, ""
    lines, quarters = [], 0
    with subprocess.Popen(command, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                          text=True) as p:
        for line in p.stdout:
            lines.append(line)
            m = NINJA_PROGRESS.match(line)
            if m and 4 * int(m[1]) >= (quarters + 1) * int(m[2]) and quarters < 4:
                quarters = 4 * int(m[1]) // int(m[2])
                print(f"{name}: {m[1]} of {m[2]} build steps", file=sys.stderr, flush=True)
    return p.returncode, "".join(lines)


def _last_lines(*texts, n: int = 25) -> str:
    lines = "\n".join(t or "" for t in texts).strip().splitlines()
    return "\n".join(lines[-n:])


def main(argv: list[str] | None = None) -> int:
    import argparse

    p = argparse.ArgumentParser(prog="python -m corobot_drake.ros2.build",
                                description=__doc__.split("\n\n")[0])
    p.add_argument("--force", action="store_true", help="build even when up to date")
    p.add_argument("--verbose", action="store_true", help="show CMake's and Ninja's output")
    args = p.parse_args(argv)
    try:
        root = prefix()
        if not (root / "share" / "rosidl_default_generators").is_dir():
            raise BuildError(f"ROS 2's build wheels are not installed: {install_hint('ros2')}"
                             "; or, for a ROS 2 user's environment without the project, pip "
                             "install -r tools/ros2_user_requirements.txt")
        fix_exported_cmake(root)
        for name in PACKAGES:
            if not args.force and up_to_date(root, name):
                continue
            print(f"building {name} into {root} ...", file=sys.stderr, flush=True)
            build_package(root, name, quiet=not args.verbose)
    except BuildError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
