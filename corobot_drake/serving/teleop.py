"""Keyboard and on-screen driving from Meshcat (what the MRDS dashboard did), and its camera.

Arrow keys (or the buttons) drive at the `Power` slider's setting while held; Space stops; E
toggles enable; F toggles the follow camera (`view.FollowCamera`, on at the start).

Meshcat's page tells the server of key presses, never of releases: `Meshcat.AddButton`'s
keycode registers a keydown callback, each keydown counts a click, and there is no keyup. A
held key repeats, though (the browser's auto-repeat: after a delay of ~0.25-0.66 s by the
system's setting, a keydown every ~30-50 ms). So a move is held only while presses keep
coming: it stops `HOLD_REPEAT` s after the latest press, `HOLD_FIRST` s after a first one (the
repeat delay); a click on a button nudges the robot for `HOLD_FIRST` s. The teleop polls the
counts between simulation steps and issues commands through the Python API.
"""

import dataclasses as dc
import time

from corobot_drake.serving.view import FollowCamera
from corobot_drake.simulation import Simulation

_MOVES = {
    # button label: (keycode, (left, right) as multiples of the power slider)
    "Forward (Up)": ("ArrowUp", (1.0, 1.0)),
    "Back (Down)": ("ArrowDown", (-1.0, -1.0)),
    "Turn left (Left)": ("ArrowLeft", (-0.5, 0.5)),
    "Turn right (Right)": ("ArrowRight", (0.5, -0.5)),
}
_STOP = "Stop (Space)"
_ENABLE = "Enable/disable (E)"
_FOLLOW = "Follow camera (F)"
_POWER = "Power"
_ROBOT = "Robot #"
_DRIVING = "Driving: {}"
"""A button whose label names the robot the "Robot #" slider picks (Meshcat's slider shows
only its number; a control's label cannot change, so the button is replaced when it does)."""

HOLD_FIRST = 0.7
"""s a move lasts after a first press: past the longest usual key-repeat delay (X11's 660 ms),
so a held key's repeats arrive before it ends."""
HOLD_REPEAT = 0.25
"""s a move lasts after a repeated press: several repeat intervals (30-50 ms; 100 ms on slow
settings), and what a release takes to stop the robot (plus one poll)."""


@dc.dataclass
class _Held:
    """The move being held: its button, the robot it drives, the (left, right) power issued,
    and the wall-clock time (s) it ends unless pressed again."""

    label: str
    robot: str
    powers: tuple[float, float]
    until: float


class MeshcatTeleop:
    """Polls Meshcat's buttons and sliders, drives the selected robot, moves the camera."""

    def __init__(self, meshcat, sim: Simulation, clock=time.monotonic):
        """`clock`: wall-clock seconds (key repeats are in real time, not simulated)."""
        self._meshcat = meshcat
        self._sim = sim
        self._clock = clock
        self._names = list(sim.robots)
        for label, (keycode, _) in _MOVES.items():
            meshcat.AddButton(label, keycode)
        meshcat.AddButton(_STOP, "Space")
        meshcat.AddButton(_ENABLE, "KeyE")
        meshcat.AddButton(_FOLLOW, "KeyF")
        meshcat.AddSlider(_POWER, 0.0, 1.0, 0.05, 0.5)
        self._shown = None
        if len(self._names) > 1:
            meshcat.AddSlider(_ROBOT, 0, len(self._names) - 1, 1, 0)
            self._show_robot()
        self._clicks = {label: 0 for label in (*_MOVES, _STOP, _ENABLE, _FOLLOW)}
        self._held: _Held | None = None
        self.camera = FollowCamera(meshcat, sim, self._robot().position())

    def _robot(self):
        index = int(self._meshcat.GetSliderValue(_ROBOT)) if len(self._names) > 1 else 0
        return self._sim.robot(self._names[index])

    def _show_robot(self) -> None:
        """Names the selected robot on the "Driving: ..." button (if it changed)."""
        name = self._robot().name
        if name == self._shown:
            return
        if self._shown is not None:
            self._meshcat.DeleteButton(_DRIVING.format(self._shown), strict=False)
        self._meshcat.AddButton(_DRIVING.format(name))
        self._shown = name

    def poll(self) -> None:
        """Issues a command for each button pressed since the last poll, stops a move whose
        key is no longer held, and carries the follow camera along."""
        now = self._clock()
        if self._shown is not None:
            self._show_robot()
        for label in self._clicks:
            clicks = self._meshcat.GetButtonClicks(label)
            if clicks == self._clicks[label]:
                continue
            self._clicks[label] = clicks
            robot = self._robot()
            if label in _MOVES:
                self._press(label, robot, now)
            elif label == _STOP:
                self._held = None
                robot.all_stop()
            elif label == _ENABLE:
                robot.enable(not robot.enable_requested())
            else:
                self.camera.toggle(robot.position(), now)
        if self._held is not None and now > self._held.until:
            self._sim.robot(self._held.robot).all_stop()
            self._held = None
        self.camera.update(self._robot().position(), now)

    def _press(self, label: str, robot, now: float) -> None:
        """Holds the move of `label`: a repeat of the held one extends it (and re-issues it
        only if the power slider moved); another starts it."""
        power = self._meshcat.GetSliderValue(_POWER)
        left, right = _MOVES[label][1]
        powers = (left * power, right * power)
        held = self._held
        repeat = held is not None and (held.label, held.robot) == (label, robot.name)
        if not (repeat and held.powers == powers):
            robot.set_power(*powers)
        self._held = _Held(label, robot.name, powers,
                           now + (HOLD_REPEAT if repeat else HOLD_FIRST))
