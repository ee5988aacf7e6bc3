"""An X display for Drake's `RenderEngineGl`, which renders through GLX.

`x_display()` returns the display the GL renderer will use: the user's `$DISPLAY` when it can
be opened, else a private `Xvfb` (Debian package `xvfb`; `tools/setup` installs it) started
once for this process, which then exports its `DISPLAY` (a stale `$DISPLAY`, e.g. from an
ended `ssh -X`, is replaced, with a warning). Without either it returns None and the camera
falls back to VTK (EGL, no X server needed, ~2x the cost per frame here).

The private server lives exactly as long as this process: it runs with `-terminate` (it exits
when its last client disconnects) and this module keeps a connection to it open until the
process ends, however it ends. Drake also opens the display once per process and keeps it.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import functools
import os
import select
import shutil
import subprocess
import warnings

XVFB_ARGS = ("-nolisten", "tcp", "-screen", "0", "64x64x24", "-terminate")
"""GL renders into its own framebuffers, so the screen only has to exist; `-terminate`: exit
when the last client disconnects."""

START_TIMEOUT = 10.0
"""s to wait for Xvfb to report its display number."""

_xvfb: subprocess.Popen | None = None
"""The private X server of this process, once started (a process resource, like the display
connection Drake keeps)."""

_keepalive = None
"""This process's own connection to the private server (an Xlib Display*), held open so the
server, which exits with its last client, outlives every other client of this process."""


@functools.cache
def _xlib():
    name = ctypes.util.find_library("X11")
    if name is None:
        return None
    lib = ctypes.CDLL(name)
    lib.XOpenDisplay.argtypes = [ctypes.c_char_p]
    lib.XOpenDisplay.restype = ctypes.c_void_p
    lib.XCloseDisplay.argtypes = [ctypes.c_void_p]
    return lib


def can_open(display: str) -> bool:
    """Whether X display `display` accepts a connection (opened and closed at once)."""
    xlib = _xlib()
    if xlib is None:
        return False
    connection = xlib.XOpenDisplay(display.encode())
    if not connection:
        return False
    xlib.XCloseDisplay(connection)
    return True


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


def start_xvfb() -> str | None:
    """Starts a private Xvfb (once per process) and returns its DISPLAY, or None when `Xvfb`
    or Xlib is not installed or the server does not start."""
    global _xvfb, _keepalive
    if _xvfb is not None and _xvfb.poll() is None:
        return f":{_xvfb.display_number}"
    executable, xlib = shutil.which("Xvfb"), _xlib()
    if executable is None or xlib is None:
        return None
    read_end, write_end = os.pipe()
    try:
        process = subprocess.Popen(
            [executable, "-displayfd", str(write_end), *XVFB_ARGS], pass_fds=(write_end,),
            stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
            start_new_session=True)
    except OSError:
        os.close(read_end)
        return None
    finally:
        os.close(write_end)
    connection = None
    try:  # until a connection is open, nothing else ends the server (`-terminate`)
        number = _read_display_number(read_end)
        connection = xlib.XOpenDisplay(f":{number}".encode()) if number is not None else None
    finally:  # also on a Ctrl-C meanwhile
        if not connection:
            process.kill()
            process.wait()
    if not connection:
        return None
    process.display_number = number
    _xvfb, _keepalive = process, connection
    return f":{number}"


def x_display() -> str | None:
    """The X display GL rendering uses: `$DISPLAY` if it can be opened, else a private Xvfb's
    (exported to `$DISPLAY`), else None."""
    user = os.environ.get("DISPLAY")
    if user and ((_xvfb is not None and user == f":{_xvfb.display_number}") or can_open(user)):
        return user
    display = start_xvfb()
    if display is not None:
        if user:
            warnings.warn(f"DISPLAY={user} cannot be opened; rendering on a private Xvfb "
                          f"({display})", stacklevel=2)
        os.environ["DISPLAY"] = display
    return display
