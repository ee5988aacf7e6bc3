"""tools/setup says what it does: its apt step waits for a held apt lock (a bounded wait, then
one line naming the holder) instead of failing at once as apt-get does (status 100), and its
pip, apt and ROS 2 steps turn their tools' output into progress lines.

The script is sourced (it then only defines its functions) and each function runs on its own:
the lock is a POSIX lock (as apt's) on a file of the test's, held by a child process."""

import subprocess
import sys
import time

import pytest

from conftest import REPO

SETUP = REPO / "tools" / "setup"
HOLDER = """
import fcntl, sys, time
lock = open(sys.argv[1], "w")
fcntl.lockf(lock, fcntl.LOCK_EX)
print("held", flush=True)
time.sleep(float(sys.argv[2]))
"""


def run_function(call: str, env: dict | None = None, stdin: str = "", timeout: float = 60):
    """`call` in a bash that sourced tools/setup: the finished process."""
    return subprocess.run(["bash", "-c", f'source "{SETUP}"; {call}'], input=stdin,
                          capture_output=True, text=True, env=env, timeout=timeout, cwd=REPO)


@pytest.fixture
def held_lock(tmp_path):
    """(the lock file, a function starting a holder for s seconds: its Popen)."""
    path = tmp_path / "lock-frontend"
    path.touch()
    holders = []

    def hold(seconds: float):
        p = subprocess.Popen([sys.executable, "-c", HOLDER, str(path), str(seconds)],
                             stdout=subprocess.PIPE, text=True)
        holders.append(p)
        assert p.stdout.readline().strip() == "held"
        return p

    yield path, hold
    for p in holders:
        p.kill()
        p.wait()


def test_sourcing_runs_nothing():
    done = run_function("echo sourced")
    assert (done.returncode, done.stdout, done.stderr) == (0, "sourced\n", "")


def run_setup(tmp_path, *args: str):
    """tools/setup `args`, copied into an empty clone at tmp_path whose PATH has no Python (so
    were the arguments not refused it could install nothing, but fail at its first step)."""
    import shutil

    (tmp_path / "tools").mkdir()
    shutil.copy(SETUP, tmp_path / "tools" / "setup")
    bin_dir = tmp_path / "bin"
    bin_dir.mkdir()
    for tool in ("bash", "sed", "dirname", "du", "cut", "rm"):
        (bin_dir / tool).symlink_to(shutil.which(tool))
    return subprocess.run([str(bin_dir / "bash"), str(tmp_path / "tools" / "setup"), *args],
                          capture_output=True, text=True, timeout=60, cwd=tmp_path,
                          env={"PATH": str(bin_dir), "PYTHON": str(tmp_path / "none")})


@pytest.mark.parametrize("flag", ["-h", "--help"])
def test_help_prints_the_header_comment_and_installs_nothing(tmp_path, flag):
    done = run_setup(tmp_path, flag)
    lines = SETUP.read_text().splitlines()[1:]
    header = lines[:next(i for i, line in enumerate(lines) if not line.startswith("#"))]
    assert (done.returncode, done.stderr) == (0, "")
    assert done.stdout.splitlines() == [line[2:] for line in header]
    assert "Sets up corobot-drake" in done.stdout and "--help" in done.stdout
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bin", "tools"]


def test_an_unknown_argument_is_one_line_and_status_2(tmp_path):
    done = run_setup(tmp_path, "--yes")
    assert (done.returncode, done.stdout) == (2, "")
    assert done.stderr == "error: tools/setup takes no arguments but -h or --help (given: --yes)\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bin", "tools"]


def test_the_apt_step_waits_for_a_held_lock_and_goes_on(held_lock):
    path, hold = held_lock
    holder = hold(3.0)
    start = time.monotonic()
    done = run_function("wait_for_apt; echo free",
                        env={"PATH": "/usr/bin:/bin", "APT_LOCKS": f"/nonexistent {path}",
                             "APT_LOCK_WAIT": "60"})
    waited = time.monotonic() - start
    assert done.returncode == 0, done.stderr
    assert done.stdout == "free\n"
    lines = done.stderr.splitlines()
    assert f"held by process {holder.pid}" in lines[0] and "up to 60 s" in lines[0]
    assert lines[1].startswith("  apt's lock is free after") and len(lines) == 2
    assert 1.0 < waited < 20.0  # the holder's 3 s less its start, plus a 2 s poll at most


def test_the_apt_step_gives_up_after_its_bound_with_one_line(held_lock):
    path, hold = held_lock
    holder = hold(60.0)
    start = time.monotonic()
    done = run_function("wait_for_apt; echo not reached",
                        env={"PATH": "/usr/bin:/bin", "APT_LOCKS": str(path),
                             "APT_LOCK_WAIT": "2"})
    assert time.monotonic() - start < 15.0
    assert done.returncode == 1 and done.stdout == ""
    errors = [line for line in done.stderr.splitlines() if line.startswith("error:")]
    assert len(errors) == 1
    assert f"process {holder.pid} holds its lock" in errors[0] and "after 2 s" in errors[0]
    assert "run tools/setup again" in errors[0]


def test_a_free_lock_is_not_waited_for(tmp_path):
    (tmp_path / "lock").touch()
    done = run_function("wait_for_apt; echo free",
                        env={"PATH": "/usr/bin:/bin", "APT_LOCKS": str(tmp_path / "lock")})
    assert (done.returncode, done.stdout, done.stderr) == (0, "free\n", "")


PIP_OUTPUT = """\
Obtaining file:///work/main
Collecting drake<2,>=1.58
  Downloading drake-1.58.0-cp312-abi3-manylinux_2_34_x86_64.whl (300 MB)
Requirement already satisfied: numpy>=1.24 in ./.venv/lib/python3.13/site-packages
Collecting ray<3,>=2.40
Installing collected packages: ray, drake, corobot_drake
Successfully installed corobot_drake-0.1.0 drake-1.58.0 ray-2.50.0
"""


def test_pips_output_becomes_a_line_per_package(tmp_path):
    log = tmp_path / "pip.log"
    done = run_function(f'pip_progress "{log}"', stdin=PIP_OUTPUT)
    assert done.stdout.splitlines() == ["  1: drake<2,>=1.58", "  2: ray<3,>=2.40",
                                        "  installing 3 packages ...", "  installed 3 packages"]
    assert log.read_text() == PIP_OUTPUT


APT_OUTPUT = """\
Reading package lists...
Building dependency tree...
Reading state information...
The following NEW packages will be installed:
  cmake cmake-data libarchive13 libjsoncpp25 librhash0 libuv1 ninja-build
0 upgraded, 7 newly installed, 0 to remove and 0 not upgraded.
Need to get 13.6 MB of archives.
After this operation, 51.0 MB of additional disk space will be used.
Get:1 http://deb.debian.org/debian bookworm/main amd64 libarchive13 amd64 3.6.2-1+deb12u5 [343 kB]
Fetched 13.6 MB in 2s (6,123 kB/s)
Selecting previously unselected package libarchive13:amd64.
(Reading database ... 100%(Reading database ... 6089 files and directories currently installed.)
Preparing to unpack .../0-libarchive13_3.6.2-1+deb12u5_amd64.deb ...
Unpacking libarchive13:amd64 (3.6.2-1+deb12u5) ...
Selecting previously unselected package libjsoncpp25:amd64.
Preparing to unpack .../1-libjsoncpp25_1.9.5-4_amd64.deb ...
Unpacking libjsoncpp25:amd64 (1.9.5-4) ...
Unpacking librhash0:amd64 (1.4.3-3) ...
Unpacking libuv1:amd64 (1.44.2-1+deb12u1) ...
Unpacking cmake-data (3.25.1-1) ...
Preparing to unpack .../5-cmake_3.25.1-1_amd64.deb ...
Unpacking cmake (3.25.1-1) ...
Unpacking ninja-build (1.11.1-2~deb12u1) ...
Setting up libarchive13:amd64 (3.6.2-1+deb12u5) ...
Setting up ninja-build (1.11.1-2~deb12u1) ...
Setting up libuv1:amd64 (1.44.2-1+deb12u1) ...
Setting up libjsoncpp25:amd64 (1.9.5-4) ...
Setting up librhash0:amd64 (1.4.3-3) ...
Setting up cmake-data (3.25.1-1) ...
Setting up cmake (3.25.1-1) ...
Processing triggers for man-db (2.11.2-2) ...
Processing triggers for libc-bin (2.36-9+deb12u14) ...
"""
"""`apt-get -q install -y --no-install-recommends cmake ninja-build`: apt's lines in its own
words, dpkg's as this machine's /var/log/apt/term.log recorded that install (a few of its
"Selecting"/"Preparing" lines left out)."""


def test_apts_output_becomes_a_line_per_package(tmp_path):
    log = tmp_path / "apt.log"
    done = run_function(f'apt_progress "{log}"', stdin=APT_OUTPUT)
    assert done.returncode == 0, done.stderr
    assert done.stdout.splitlines() == [
        "  downloading 13.6 MB ...", "  downloaded 13.6 MB in 2s",
        *(f"  {i}/7: {name}" for i, name in enumerate((
            "libarchive13", "libjsoncpp25", "librhash0", "libuv1", "cmake-data", "cmake",
            "ninja-build"), start=1)),
        "  setting up the packages ...", "  set up 7 packages"]
    assert log.read_text() == APT_OUTPUT


def test_the_ros2_build_lines_get_their_time():
    done = run_function("printf 'building tf2_msgs into /x ...\\n' | with_elapsed")
    assert done.stderr == "  [0 s] building tf2_msgs into /x ...\n"
    done = run_function("with_elapsed < /dev/null")
    assert done.stderr == "  built already, from the same sources\n"


def test_the_ros2_build_says_each_quarter_of_a_package(capsys):
    from corobot_drake.ros2.build import run_step

    ninja = "for i in $(seq 1 10); do echo \"[$i/10] Building $i\"; done; echo note >&2"
    status, output = run_step(["bash", "-c", ninja], {"PATH": "/usr/bin:/bin"}, True, "pkg")
    assert status == 0 and output.splitlines()[-1] == "note" and "[10/10] Building 10" in output
    assert capsys.readouterr().err.splitlines() == [
        "pkg: 3 of 10 build steps", "pkg: 5 of 10 build steps", "pkg: 8 of 10 build steps",
        "pkg: 10 of 10 build steps"]
    status, output = run_step(["bash", "-c", "echo why; exit 3"], {"PATH": "/usr/bin:/bin"},
                              True, "pkg")
    assert (status, output) == (3, "why\n")


FAKE_PYTHON = """#!/usr/bin/env bash
echo "$* | hook ${_ROS_WHEELS_BOOTSTRAP_COMPLETE-unset} | libraries ${LD_LIBRARY_PATH-unset}" \\
  >> "$(dirname "$0")/calls"
"""


def test_the_ros_users_environment_runs_without_the_project_pythons_variables(tmp_path):
    """The ROS 2 user's step calls .venv-ros's Python (here a stand-in that notes how it was
    called) without the variables of the project's Python (the wheels' start-up hook's mark,
    its ROS libraries' path), which would otherwise keep .venv's ROS libraries in it; an
    environment installed since the requirements changed is not installed again."""
    python = tmp_path / ".venv-ros" / "bin" / "python"
    python.parent.mkdir(parents=True)
    python.write_text(FAKE_PYTHON)
    python.chmod(0o755)
    (tmp_path / "tools").mkdir()
    (tmp_path / "tools" / "ros2_user_requirements.txt").write_text("ros-jazzy-rclpy\n")
    (tmp_path / ".venv-ros" / ".installed").touch()
    done = subprocess.run(
        ["bash", "-c", f'source "{SETUP}"; ros_user_environment'], cwd=tmp_path,
        capture_output=True, text=True, timeout=60,
        env={"PATH": "/usr/bin:/bin", "_ROS_WHEELS_BOOTSTRAP_COMPLETE": "1",
             "LD_LIBRARY_PATH": "/project/.venv/lib"})
    assert done.returncode == 0, done.stderr
    lines = done.stderr.splitlines()
    assert lines[0].startswith("[1/5] A ROS 2 user's environment: .venv-ros")
    assert lines[1:] == ["  installed already (tools/ros2_user_requirements.txt has not "
                         "changed since)", "  built already, from the same sources"]
    assert (python.parent / "calls").read_text().splitlines() == [
        "-c import rclpy | hook unset | libraries unset",
        "-m corobot_drake.ros2.build | hook unset | libraries unset"]


DEBIAN_PYTHON = """#!/bin/bash
# A Debian Python without its -venv package until apt-get (below) "installs" it.
here="$(dirname "$0")"
if [ "$1" = -m ] && [ "$2" = venv ]; then
  mkdir -p "$3/bin" && touch "$3/bin/python"
  [ -e "$here/installed" ] && exit 0
  echo "The virtual environment was not created successfully because ensurepip is not" \\
       "available." >&2
  exit 1
elif [ "$2" = "import ensurepip" ]; then
  [ -e "$here/installed" ]
else
  echo 3.12
fi
"""
FAKE_APT_GET = """#!/bin/bash
echo "$@" >> "$(dirname "$0")/apt-get.args"
touch "$(dirname "$0")/installed"
"""


@pytest.fixture
def debian_python(tmp_path):
    """(bin folder with a fake python3.12 lacking ensurepip and a fake apt-get, a function
    setting the user id `id -u` gives)."""
    bin_dir = tmp_path / "bin"
    bin_dir.mkdir()
    for name, text in (("python3.12", DEBIAN_PYTHON), ("apt-get", FAKE_APT_GET)):
        (bin_dir / name).write_text(text)
        (bin_dir / name).chmod(0o755)

    def as_user(uid: int):
        (bin_dir / "id").write_text(f"#!/bin/bash\necho {uid}\n")
        (bin_dir / "id").chmod(0o755)
    return bin_dir, as_user


def make_venv_with(bin_dir, venv):
    return run_function(f'make_venv_with "{bin_dir}/python3.12" "{venv}"; echo made',
                        env={"PATH": f"{bin_dir}:/usr/bin:/bin", "APT_LOCKS": "/nonexistent"})


def test_a_python_without_ensurepip_gets_its_venv_package_as_root(debian_python, tmp_path):
    bin_dir, as_user = debian_python
    as_user(0)
    done = make_venv_with(bin_dir, tmp_path / "venv")
    assert done.returncode == 0 and done.stdout == "made\n", done.stderr
    assert (bin_dir / "apt-get.args").read_text().split()[-1] == "python3.12-venv"
    assert "installing Debian's python3.12-venv" in done.stderr
    assert (tmp_path / "venv" / "bin" / "python").exists()


def test_without_root_it_names_the_package_in_one_line_and_leaves_no_half_venv(
        debian_python, tmp_path):
    bin_dir, as_user = debian_python
    as_user(1000)
    done = make_venv_with(bin_dir, tmp_path / "venv")
    assert done.returncode == 1 and done.stdout == ""
    errors = [line for line in done.stderr.splitlines() if line.startswith("error:")]
    assert errors == [f"error: {bin_dir}/python3.12 makes no virtual environment without "
                      "Debian's python3.12-venv: sudo apt-get install python3.12-venv, then "
                      "tools/setup again"]
    assert not (tmp_path / "venv").exists()  # a rerun must not take it for a made .venv
    assert not (bin_dir / "apt-get.args").exists()
