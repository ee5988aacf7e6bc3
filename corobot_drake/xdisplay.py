"""An X display for Drake's `RenderEngineGl`, which renders through GLX.

`x_display()` returns the display the GL renderer will use: the user's `$DISPLAY` when one is
set, else a private `Xvfb` (Debian package `xvfb`; `tools/setup` installs it) started once for
this process, which then exports its `DISPLAY`. Without either it returns None and the camera
falls back to VTK (EGL, no X server needed, ~2x the cost per frame here).

Drake opens the X display once per process and keeps the connection, so the private server
must outlive it: it runs with `-terminate` and exits by itself when its last client (this
process, however it ends) disconnects. `stop_xvfb` stops one that nothing connected to.
"""

from __future__ import annotations

import os
import select
import shutil
import subprocess

XVFB_ARGS = ("-nolisten", "tcp", "-screen", "0", "64x64x24", "-terminate")
"""GL renders into its own framebuffers, so the screen only has to exist; `-terminate`: exit
when the last client disconnects."""

START_TIMEOUT = 10.0
"""s to wait for Xvfb to report its display number."""

_xvfb: subprocess.Popen | None = None
"""The private X server of this process, once started (a process resource, like the display
connection Drake keeps)."""

_xvfb_display: str | None = None


def stop_xvfb() -> None:
    """Stops the private Xvfb (only safe while nothing is connected to it: Xlib ends a process
    whose display goes away) and forgets its DISPLAY."""
    global _xvfb
    if _xvfb is None:
        return
    if _xvfb.poll() is None:
        _xvfb.terminate()
        try:
            _xvfb.wait(timeout=5)
        except subprocess.TimeoutExpired:
            _xvfb.kill()
            _xvfb.wait()
    if os.environ.get("DISPLAY") == _xvfb_display:
        del os.environ["DISPLAY"]
    _xvfb = None


def start_xvfb() -> str | None:
    """Starts a private Xvfb (once per process) and returns its DISPLAY, or None when `Xvfb`
    is not installed or does not start."""
    global _xvfb, _xvfb_display
    if _xvfb is not None and _xvfb.poll() is None:
        return os.environ.get("DISPLAY")
    executable = shutil.which("Xvfb")
    if executable is None:
        return None
    read_end, write_end = os.pipe()
    try:
        process = subprocess.Popen(
            [executable, "-displayfd", str(write_end), *XVFB_ARGS], pass_fds=(write_end,),
            stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
            start_new_session=True)
    finally:
        os.close(write_end)
    number = _read_display_number(read_end)
    if number is None:
        process.kill()
        process.wait()
        return None
    _xvfb, _xvfb_display = process, f":{number}"
    return _xvfb_display


def _read_display_number(fd: int) -> str | None:
    """The number Xvfb writes to `-displayfd` once it accepts connections (None on timeout or
    if it exits first: the pipe closes)."""
    data = b""
    with os.fdopen(fd, "rb", buffering=0) as pipe:
        while not data.endswith(b"\n"):
            ready, _, _ = select.select([pipe], [], [], START_TIMEOUT)
            chunk = pipe.read(16) if ready else b""
            if not chunk:
                return None
            data += chunk
    number = data.strip().decode()
    return number if number.isdigit() else None


def x_display() -> str | None:
    """The X display GL rendering uses: `$DISPLAY` if set, else a private Xvfb's (exported to
    `$DISPLAY`), else None."""
    if os.environ.get("DISPLAY"):
        return os.environ["DISPLAY"]
    display = start_xvfb()
    if display is not None:
        os.environ["DISPLAY"] = display
    return display
