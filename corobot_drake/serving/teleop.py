"""Keyboard and on-screen driving from Meshcat (what the MRDS dashboard did).

Arrow keys (or the buttons) drive at the `Power` slider's setting; Space stops; E toggles
enable. Meshcat counts clicks and key presses, so the teleop polls those counts between
simulation steps and issues a command through the Python API when one changes.
"""

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
_POWER = "Power"
_ROBOT = "Robot #"


class MeshcatTeleop:
    """Polls Meshcat's buttons and sliders and drives the selected robot."""

    def __init__(self, meshcat, sim: Simulation):
        self._meshcat = meshcat
        self._sim = sim
        self._names = list(sim.robots)
        for label, (keycode, _) in _MOVES.items():
            meshcat.AddButton(label, keycode)
        meshcat.AddButton(_STOP, "Space")
        meshcat.AddButton(_ENABLE, "KeyE")
        meshcat.AddSlider(_POWER, 0.0, 1.0, 0.05, 0.5)
        if len(self._names) > 1:
            meshcat.AddSlider(_ROBOT, 0, len(self._names) - 1, 1, 0)
        self._clicks = {label: 0 for label in (*_MOVES, _STOP, _ENABLE)}

    def _robot(self):
        index = int(self._meshcat.GetSliderValue(_ROBOT)) if len(self._names) > 1 else 0
        return self._sim.robot(self._names[index])

    def poll(self) -> None:
        """Issues a command for each button pressed since the last poll."""
        power = self._meshcat.GetSliderValue(_POWER)
        for label in self._clicks:
            clicks = self._meshcat.GetButtonClicks(label)
            if clicks == self._clicks[label]:
                continue
            self._clicks[label] = clicks
            robot = self._robot()
            if label == _STOP:
                robot.all_stop()
            elif label == _ENABLE:
                robot.enable(not robot.enable_requested())
            else:
                left, right = _MOVES[label][1]
                robot.set_power(left * power, right * power)
