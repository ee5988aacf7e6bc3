"""Each wheel's slip in Meshcat: a small ball beside the tyre, green gripping, red sliding.

Drake's ContactVisualizer draws each tyre's contact force as an arrow; the ball outside each
wheel's hub says how much that wheel slips (`contact.WheelContacts`): its colour runs from
green (0) through yellow to red at full slip, `slip_severity`: the larger of |slip ratio| and
|slip angle| / 45 deg, capped at 1 (a free-rolling wheel ~0.01, a spin in place ~0.9). It is
redrawn at `MARKER_PERIOD` (10 Hz), stamped with the simulation time so a recording
(`recording.meshcat_html`) replays it; the station adds it only with a Meshcat.

A colour is a Meshcat property ("color") for the live page, but three.js animates only a
property of the object itself: the recording keys `material.color` of the ball's
`<object>` instead (a "color" track would name a property the scene node lacks, and the
replay would log a three.js error for each ball when opened).
"""

import math

from pydrake.common.value import AbstractValue
from pydrake.geometry import Meshcat, Rgba, Sphere
from pydrake.math import RigidTransform
from pydrake.systems.framework import LeafSystem

from corobot_drake.robots import corobot

MARKER_PERIOD = 0.1
"""s between redraws: 10 Hz is plenty for the eye, and eight Meshcat messages a redraw."""
MARKER_RADIUS = 0.012
"""m."""
MARKER_GAP = 0.015
"""m between the tyre's outer face and the ball's centre."""
FULL_SLIP_ANGLE_DEG = 45.0
"""deg: a slip angle that counts as full slip (the wheel goes as much sideways as along)."""


def slip_severity(ratio: float, angle_deg: float) -> float:
    """0 (gripping) to 1 (full slip): max(|ratio|, |angle| / 45 deg), capped at 1."""
    return min(1.0, max(abs(ratio), abs(angle_deg) / FULL_SLIP_ANGLE_DEG))


def severity_rgba(severity: float) -> list[float]:
    """Green (0) through yellow (0.5) to red (1), opaque: [r, g, b, a]."""
    return [min(1.0, 2.0 * severity), min(1.0, 2.0 * (1.0 - severity)) * 0.8, 0.0, 1.0]


class SlipMarkers(LeafSystem):
    """One robot's slip balls in Meshcat (module docstring).

    .. pydrake_system::

        name: SlipMarkers
        input_ports:
        - chassis_pose
        - wheel_slip_ratio
        - wheel_slip_angle

    Inputs: `chassis_pose` (abstract RigidTransform X_WC), `wheel_slip_ratio` and
    `wheel_slip_angle` (one per wheel each, deg, the robot's wheel order, from
    `contact.WheelContacts`). Draws `<path>/<wheel>` (spheres) every `MARKER_PERIOD` s from
    time 0; no state (the balls are drawn from the inputs alone). `record`: whether `meshcat`
    is recording (None: no; True: recording and showing live; False: recording only), as
    `Simulation` starts it (`recording.meshcat_html.start_recording`). `spec`: the robot's
    `robots.RobotSpec` (None: the Corobot's wheels).
    """

    def __init__(self, meshcat: Meshcat, path: str, record: bool | None = None, spec=None):
        super().__init__()
        self._meshcat = meshcat
        self.path = path
        self._record = record
        if spec is None:
            spec = corobot.spec()
        wheels = [(w.short, w.center, w.width) for w in spec.wheels]
        self._names = [name for name, _, _ in wheels]
        self._pose = self.DeclareAbstractInputPort("chassis_pose",
                                                   AbstractValue.Make(RigidTransform()))
        self._ratio = self.DeclareVectorInputPort("wheel_slip_ratio", len(wheels))
        self._angle = self.DeclareVectorInputPort("wheel_slip_angle", len(wheels))
        self.DeclarePeriodicPublishEvent(MARKER_PERIOD, 0.0, self._draw)
        self._X_CM = {}  # each ball in the chassis frame: outside its wheel's hub
        for name, (x, y, z), width in wheels:
            outward = width / 2 + MARKER_GAP
            self._X_CM[name] = RigidTransform([x, y + math.copysign(outward, y), z])
            meshcat.SetObject(f"{path}/{name}", Sphere(MARKER_RADIUS), Rgba(0.0, 0.8, 0.0, 1.0))

    def _draw(self, context) -> None:
        X_WC = self._pose.Eval(context)
        t = context.get_time()
        ratios, angles = self._ratio.Eval(context), self._angle.Eval(context)
        animation = self._meshcat.get_mutable_recording() if self._record is not None else None
        for k, name in enumerate(self._names):
            path = f"{self.path}/{name}"
            self._meshcat.SetTransform(path, X_WC @ self._X_CM[name], t)
            rgba = severity_rgba(slip_severity(ratios[k], angles[k]))
            if self._record is not False:  # someone may watch: the live page
                self._meshcat.SetProperty(path, "color", rgba)
            if animation is not None:  # opaque: the colour alone (three.js's Color is RGB)
                animation.SetProperty(animation.frame(t), f"{path}/<object>", "material.color",
                                      rgba[:3])


def add_slip_markers(builder, meshcat: Meshcat, name: str, chassis_pose_port, wheel_contacts,
                     record: bool | None = None, spec=None):
    """Adds `<name>.slip_markers` (drawing under `/slip/<name>`) fed by `chassis_pose_port`
    and `wheel_contacts`' slip ports; returns it. `record`, `spec`: see `SlipMarkers`."""
    system = builder.AddNamedSystem(f"{name}.slip_markers",
                                    SlipMarkers(meshcat, f"/slip/{name}", record, spec))
    builder.Connect(chassis_pose_port, system.GetInputPort("chassis_pose"))
    for port in ("wheel_slip_ratio", "wheel_slip_angle"):
        builder.Connect(wheel_contacts.GetOutputPort(port), system.GetInputPort(port))
    return system
