"""The bumper: a contact switch on a link of the robot, pressed when its collision geometry
touches anything but the ground, reporting the contact force.

By default (`BumperConfig.geometry: box`) the bumper is a box of its own
(`BumperConfig.size`), fixed to a link by its `X_PB`: the bumper frame S at the box's centre,
+x out of its face. By default it spans the Corobot's front, 5 mm ahead of the front tyres
(which stick out 44 mm past the chassis), as wide as the outer faces of the wheels, from 1.5
to 4 cm above the ground: under the front camera's view and the IR sensors' beams. It adds no
mass. With `geometry: link` the bumper is the link itself: the collision geometry the link's
model gives it (a robot whose front link is its bumper, or the Corobot's chassis), no box
added; `X_PB` then only places S, the frame of the force and of its messages.

A box is added before the plant is finalized (`BumperKind.add_geometry`): a collision box
(compliant hydroelastic rubber, low friction, so that it meets the compliant world bodies,
rigid meshes and the rigid ground hydroelastically under `hydroelastic_with_fallback`, and
slides along a wall rather than grabbing it) and a visual box of the same size.

The `Bumper` system samples the plant's contact results at its rate (a periodic discrete
update, and one at initialization), never at every physics step: the force on the bumper is
the sum of the contact forces (hydroelastic surfaces and point pairs) between its geometry
and every geometry but the ground's (the world's half-spaces), expressed in S. It is pressed when
that force's magnitude exceeds `force_threshold`. On SAP's discrete plant the contact results
are the forces of the last step; on a continuous plant (CENIC) the compliant law at the
current state, computed afresh when asked: a sample asks for them only when SceneGraph's
broad phase finds something but the ground near the bumper (`Bumper.near_anything`).

Wire formats: HTTP JSON (the reading's fields); Foxglove/MCAP as JSON (`BUMPER_SCHEMA`:
foxglove-sdk has no contact message); ROS 2 as `geometry_msgs/msg/WrenchStamped`: ROS 2 has
no standard contact or bumper message (Gazebo's, the Create 3's and the Kobuki's are their
own packages), and a WrenchStamped is the standard message of a measured force: stamped, in
the bumper's frame (on /tf_static), the force in N (torque 0). Beside it,
`bumper/<sensor>/pressed` is a `std_msgs/msg/Bool` (reliable), so that a subscriber need not
know the force threshold: it is published with every sample, as the WrenchStamped (same
time, in the bag too), not only when it changes: a level, like a driver's state topics, so a
subscriber that joins late (or a bag read from the middle) has it within one sample, with no
transient-local QoS, and an edge is two consecutive messages that differ.

Meshcat: the bumper's visual box turns red while pressed, in the live page and the `--record`
replay (`BumperMeshcat`); a `geometry: link` bumper, with no box of its own to colour, shows a
translucent red shell of its link's collision shapes while pressed (`draw_shell`).
"""

import dataclasses as dc
import math

import numpy as np
from pydrake.common.schema import Transform
from pydrake.common.value import AbstractValue, Value
from pydrake.geometry import (
    AddCompliantHydroelasticProperties,
    AddContactMaterial,
    Box,
    HalfSpace,
    ProximityProperties,
    QueryObject,
    Rgba,
)
from pydrake.math import RigidTransform
from pydrake.multibody.plant import ContactResults, CoulombFriction
from pydrake.systems.framework import EventStatus, LeafSystem

from corobot_drake.config.poses import mount, mount_frame
from corobot_drake.limits import RATE, OneOf, Range, bounded
from corobot_drake.robots import robot_spec
from corobot_drake.sensors.follow import FollowFrame
from corobot_drake.sensors.kind import BuiltSensor, SensorKind
from corobot_drake.sensors.ticks import tick_in_step
from corobot_drake.topics import nanoseconds

# --- the config (the scenario's `robots.<name>.bumpers.<sensor>`) --------------------------

CLEARANCE = 0.005
"""m: the gap between the front tyres' reach and the default bumper's back face."""
GROUND_CLEARANCE = 0.015
"""m: the default bumper's bottom above the ground."""
THICKNESS, HEIGHT = 0.02, 0.025
"""m: the default box's extent along S's x and z."""
GEOMETRIES = ("box", "link")
"""`BumperConfig.geometry`: a box of the bumper's own, or its link's own collision geometry."""


def default_size() -> tuple[float, float, float]:
    """m: the default box (thickness along S's x, width along y, height along z): 2 cm
    thick, as wide as the Corobot's wheels' outer faces (0.2794 m, its robot spec's), 2.5 cm
    high."""
    spec = robot_spec()  # the Corobot's, as its robot file and model say
    return (THICKNESS, 2 * (spec.half_track + spec.wheels[0].width / 2), HEIGHT)


def default_front() -> tuple[float, float, float]:
    """m: the default bumper's centre in the chassis frame, (0.1674, 0, 0.0275): ahead of
    the Corobot's front tyres (x = 0.1524), low: its top (0.04 m) is under the front
    camera's view (its lower edge passes 0.0412 m above the ground over the bumper's face)
    and the IR sensors' beams."""
    spec = robot_spec()
    return (spec.wheelbase / 2 + spec.wheel_radius + CLEARANCE + THICKNESS / 2, 0.0,
            GROUND_CLEARANCE + HEIGHT / 2)


@dc.dataclass
class BumperConfig:
    """One bumper on a robot."""

    X_PB: Transform = dc.field(default_factory=lambda: mount(default_front(), (0.0, 0.0, 0.0)))
    """The bumper frame S (at the box's centre, +x out of its face) in `base_frame` (default
    `chassis`: across the front, ahead of the front tyres)."""
    size: list[float] = bounded(lambda: list(default_size()),
                                Range(1e-3, 2.0, unit="m", why="a bumper's box"), size=3)
    """m: the box's extent along S's x (thickness), y (width) and z (height) (`geometry:
    box` only)."""
    geometry: str = bounded("box", OneOf(GEOMETRIES))
    """What touches: `box`, a box of its own (`size`) at S; `link`, the collision geometry
    the link of `X_PB` already has (its model's: the link is the bumper; no box is added and
    S is only the frame the force is expressed in)."""
    force_threshold: float = bounded(1.0, Range(0.0, 1e4, unit="N"))
    """N: pressed while the contact force's magnitude exceeds this."""
    rate_hz: float = bounded(50.0, RATE)
    """Samples per second (periodic discrete updates, independent of the physics step)."""
    enabled: bool = True
    """False: no bumper."""


# --- the geometry (before the plant is finalized) -------------------------------------------

FRICTION = 0.1
"""Coulomb friction of the bumper (static = dynamic): low, so it slides along what it hits."""
MODULUS = 5.0e6
"""Pa: the bumper's hydroelastic modulus, a stiff rubber strip (a world body's is 1e7)."""
DISSIPATION = 5.0
"""s/m: Hunt-Crossley dissipation (the tyres'): a knock does not bounce the robot back."""
COLOR = Rgba(0.12, 0.12, 0.12, 1.0)
"""The bumper's look at rest: black rubber."""
PRESSED_COLOR = Rgba(0.9, 0.1, 0.1, 1.0)
"""Its look in Meshcat while pressed."""


def geometry_name(name: str) -> str:
    """The bumper's geometry name on its link (its collision and visual boxes)."""
    return f"bumper_{name}"


def contact_properties(size) -> ProximityProperties:
    """Compliant hydroelastic rubber of low friction (`MODULUS`, `FRICTION`, `DISSIPATION`);
    `size` (m) gives the resolution hint a box does not use but Drake asks for."""
    props = ProximityProperties()
    AddContactMaterial(dissipation=DISSIPATION, friction=CoulombFriction(FRICTION, FRICTION),
                       properties=props)
    AddCompliantHydroelasticProperties(resolution_hint=float(min(size)),
                                       hydroelastic_modulus=MODULUS, properties=props)
    return props


def add_bumper_geometry(plant, model_instance, name: str, config: BumperConfig) -> None:
    """Registers the bumper's collision and visual boxes on the link `config.X_PB` names (a
    link of `model_instance`); the plant must not be finalized yet. With `geometry: link`,
    nothing: the link's own collision geometry is the bumper."""
    if config.geometry == "link":
        return
    body, X_BS = mount_frame(plant, model_instance, config.X_PB)
    box = Box(*config.size)
    plant.RegisterCollisionGeometry(body, X_BS, box, geometry_name(name),
                                    contact_properties(config.size))
    plant.RegisterVisualGeometry(body, X_BS, box, geometry_name(name), COLOR.rgba)


def bumper_geometries(plant, scene_graph, body, name: str) -> tuple:
    """(collision GeometryId, visual GeometryId) of the bumper `name` on `body`."""
    inspector = scene_graph.model_inspector()

    def find(ids):
        for gid in ids:
            if inspector.GetName(gid).split("::")[-1] == geometry_name(name):
                return gid
        raise ValueError(f"no bumper {name!r} on {body.name()}: add_geometry was not called")

    return (find(plant.GetCollisionGeometriesForBody(body)),
            find(plant.GetVisualGeometriesForBody(body)))


def link_geometries(plant, body, ground) -> frozenset:
    """The collision GeometryIds of `body` (a `geometry: link` bumper's: its model's) but the
    `ground`'s."""
    geometries = frozenset(plant.GetCollisionGeometriesForBody(body)) - frozenset(ground)
    if not geometries:
        raise ValueError(f"a bumper with geometry: link on {body.name()}: the link has no "
                         "collision geometry")
    return geometries


def ground_geometries(plant, scene_graph) -> frozenset:
    """The ground's GeometryIds: the world's half-spaces (whatever else touches counts)."""
    inspector = scene_graph.model_inspector()
    return frozenset(gid for gid in plant.GetCollisionGeometriesForBody(plant.world_body())
                     if isinstance(inspector.GetShape(gid), HalfSpace))


# --- the reading -------------------------------------------------------------------------


@dc.dataclass(frozen=True, repr=False)
class BumperState:
    """One bumper sample: `pressed` (the force's magnitude over the threshold), `force` (N,
    that magnitude), `force_vector` (N, the contact force on the bumper from everything but
    the ground, in the bumper frame S: +x out of its face, so a push back reads -x) and `time`
    (s, the simulated time of the sample; NaN before the first)."""

    pressed: bool
    force: float
    force_vector: tuple[float, float, float]
    time: float

    def __repr__(self) -> str:
        fx, fy, fz = self.force_vector
        return (f"BumperState(pressed={self.pressed}, force={self.force:.3f} N, "
                f"force_vector=({fx:.3f}, {fy:.3f}, {fz:.3f}) N, time={self.time:.3f} s)")


# --- the system ----------------------------------------------------------------------------

PRESSED, FORCE, FORCE_VECTOR, TIME, INDEX = 0, 1, slice(2, 5), 5, 6
STATE_SIZE = 7
"""The discrete state: [pressed (0 or 1), force (N), force vector in S (3, N), sample time
(s), sample index]."""


class Bumper(LeafSystem):
    """One bumper (module docstring): the contact force on its geometry (its box, or its
    link's own geometry), sampled at its rate.

    .. pydrake_system::

        name: Bumper
        input_ports:
        - query_object
        - contact_results
        - body_poses
        output_ports:
        - reading
        - pressed
        - force
        - force_vector
        - sample_state

    Inputs: `query_object` (abstract QueryObject, SceneGraph's), `contact_results` (abstract
    ContactResults, the plant's; read only while something but the ground is near the box,
    `near_anything`), `body_poses` (abstract list of RigidTransform X_WB by BodyIndex, the
    plant's; read only while something touches). Outputs: `reading` (abstract
    `BumperState`), `pressed` (0 or 1), `force` (N), `force_vector` (3, N, in S),
    `sample_state` (the discrete state, `STATE_SIZE`).

    Samples at initialization and every 1/`rate_hz` s from then on. With `step` (a
    continuous plant's physics step, s) each sample is taken on the plant's steps instead,
    at the first at or after its time (as the IR sensor's scans: an event between CENIC's
    steps would split one).

    geometries: the bumper's collision GeometryIds (its box's, or its link's); ground: the
    GeometryIds that do not press it; body_index: the link it is on; X_BS: S in that link's
    frame.
    """

    def __init__(self, config: BumperConfig, geometries, ground, body_index,
                 X_BS: RigidTransform, step: float = 0.0):
        super().__init__()
        self._geometries = frozenset(geometries)
        self._ground = frozenset(ground)
        self._body = int(body_index)
        self._R_BS = X_BS.rotation()
        self._threshold = float(config.force_threshold)
        self.rate = float(config.rate_hz)
        self._step = float(step)
        self._query = self.DeclareAbstractInputPort("query_object",
                                                    AbstractValue.Make(QueryObject()))
        self._contacts = self.DeclareAbstractInputPort("contact_results",
                                                       AbstractValue.Make(ContactResults()))
        self._poses = self.DeclareAbstractInputPort("body_poses",
                                                    AbstractValue.Make([RigidTransform()]))
        initial = np.zeros(STATE_SIZE)
        initial[TIME] = math.nan
        self._state = self.DeclareDiscreteState(initial)
        self.DeclareInitializationDiscreteUpdateEvent(self._first_sample)
        period = 1.0 / self.rate
        if step > 0:
            self.DeclarePeriodicDiscreteUpdateEvent(step, 0.0, self._sample_if_due)
        else:
            self.DeclarePeriodicDiscreteUpdateEvent(period, period, self._sample)
        self.events = (step, 0.0) if step > 0 else (period, period)
        """(period, offset), s: the schedule of the sample events (a publisher looking on it
        sees each sample at the look after it)."""
        state = {self.discrete_state_ticket(self._state)}
        self.DeclareAbstractOutputPort(
            "reading", lambda: Value(self.reading_of(initial)),
            lambda c, out: out.set_value(self.reading_of(self._x(c))), state)
        self.DeclareVectorOutputPort("pressed", 1, lambda c, out: out.SetAtIndex(
            0, self._x(c)[PRESSED]), state)
        self.DeclareVectorOutputPort("force", 1, lambda c, out: out.SetAtIndex(
            0, self._x(c)[FORCE]), state)
        self.DeclareVectorOutputPort("force_vector", 3, lambda c, out: out.SetFromVector(
            self._x(c)[FORCE_VECTOR]), state)
        self.DeclareStateOutputPort("sample_state", self._state)

    def _x(self, context) -> np.ndarray:
        return context.get_discrete_state(self._state).value()

    @staticmethod
    def reading_of(x) -> BumperState:
        """The reading of a state vector (`STATE_SIZE`)."""
        fx, fy, fz = (float(v) for v in x[FORCE_VECTOR])
        return BumperState(bool(x[PRESSED] > 0.5), float(x[FORCE]), (fx, fy, fz), float(x[TIME]))

    def near_anything(self, query_object) -> bool:
        """Whether anything but the ground may touch the bumper: SceneGraph's broad phase
        pairs one of its geometries with something (their bounding boxes overlap). On a
        continuous plant the contact results are computed afresh when asked (every tyre's
        contact surface): a sample asks for them only then."""
        g, ground = self._geometries, self._ground
        for a, b in query_object.FindCollisionCandidates():
            if (a in g and b not in ground) or (b in g and a not in ground):
                return True
        return False

    def force_in_world(self, results) -> tuple[float, float, float] | None:
        """N: the sum of the contact forces on the bumper's geometry from every geometry but
        the ground's, in the world; None when nothing but the ground touches it."""
        g, ground = self._geometries, self._ground
        f = [0.0, 0.0, 0.0]
        touched = False
        for i in range(results.num_hydroelastic_contacts()):
            info = results.hydroelastic_contact_info(i)
            surface = info.contact_surface()
            # F_Ac_W acts on the body of geometry M; the body of N gets its opposite.
            m, n = surface.id_M(), surface.id_N()
            if (m not in g and n not in g) or (n if m in g else m) in ground:
                continue
            sign = 1.0 if m in g else -1.0
            for k, v in enumerate(info.F_Ac_W().translational()):
                f[k] += sign * float(v)
            touched = True
        for i in range(results.num_point_pair_contacts()):
            info = results.point_pair_contact_info(i)
            pair = info.point_pair()
            # contact_force acts on body B (geometry id_B); body A gets its opposite.
            a, b = pair.id_A, pair.id_B
            if (a not in g and b not in g) or (a if b in g else b) in ground:
                continue
            sign = 1.0 if b in g else -1.0
            for k, v in enumerate(info.contact_force()):
                f[k] += sign * float(v)
            touched = True
        return tuple(f) if touched else None

    def _first_sample(self, context, discrete_state) -> None:
        self._take(context, discrete_state.get_mutable_value(), 0)

    def _sample(self, context, discrete_state) -> None:
        x = discrete_state.get_mutable_value()
        self._take(context, x, int(x[INDEX]) + 1)

    def sample_due(self, t: float) -> bool:
        """Whether the plant step at `t` (`step` > 0) takes a sample: a sample time k / rate
        (k >= 1) in (t - step, t]."""
        return tick_in_step(t, self.rate, 1.0 / self.rate, self._step)

    def _sample_if_due(self, context, discrete_state):
        if not self.sample_due(context.get_time()):
            return EventStatus.DidNothing()
        self._sample(context, discrete_state)
        return EventStatus.Succeeded()

    def _take(self, context, x, index: int) -> None:
        f_W = None
        if self.near_anything(self._query.Eval(context)):
            f_W = self.force_in_world(self._contacts.Eval(context))
        f_S = (0.0, 0.0, 0.0)
        if f_W is not None:
            R_WS = self._poses.Eval(context)[self._body].rotation() @ self._R_BS
            f_S = R_WS.inverse() @ np.array(f_W)
        force = math.sqrt(sum(v * v for v in f_S))
        x[:] = [1.0 if force > self._threshold else 0.0, force, *f_S, context.get_time(),
                index]


# --- Meshcat -------------------------------------------------------------------------------

MESHCAT_PREFIX = "/drake/illustration"
"""Where Drake's Meshcat visualizer of the visual geometry draws (`station.visualization_config`:
its prefix `drake`, the role `illustration`), each geometry at `<prefix>/<frame>/<geometry>`,
their scoped names' `::` as `/`."""


def meshcat_path(scene_graph, visual) -> str:
    """The Meshcat path of the visual geometry `visual` as Drake's visualizer draws it."""
    inspector = scene_graph.model_inspector()
    frame = inspector.GetName(inspector.GetFrameId(visual))
    return "/".join((MESHCAT_PREFIX, frame.replace("::", "/"),
                     inspector.GetName(visual).replace("::", "/")))


SHELL_COLOR = Rgba(0.9, 0.1, 0.1, 0.5)
"""The look of a `geometry: link` bumper's shell in Meshcat while pressed (translucent red)."""


def draw_shell(meshcat, path: str, scene_graph, geometries) -> None:
    """A `geometry: link` bumper's shell under `path`: a copy of each of its link's collision
    shapes (`geometries`) in `SHELL_COLOR`, in the link's frame (`path` follows the link),
    hidden until pressed. A shape Meshcat cannot draw is left out."""
    inspector = scene_graph.model_inspector()
    for k, gid in enumerate(sorted(geometries, key=lambda g: g.get_value())):
        try:
            meshcat.SetObject(f"{path}/{k}", inspector.GetShape(gid), SHELL_COLOR)
        except RuntimeError:  # e.g. a half-space: nothing to outline
            continue
        meshcat.SetTransform(f"{path}/{k}", inspector.GetPoseInFrame(gid))
    meshcat.SetProperty(path, "visible", False)


class BumperMeshcat(LeafSystem):
    """Shows a press in Meshcat: the bumper's box red while pressed, black rubber otherwise;
    a `geometry: link` bumper's shell (`draw_shell`) shown while pressed, hidden otherwise.

    .. pydrake_system::

        name: BumperMeshcat
        input_ports:
        - pressed

    Its input is a Bumper's `pressed`. At the end of every step it sets the colour of `path`
    (the box as Drake's visualizer draws it, `meshcat_path`), or with `shell` whether `path`
    (the shell) is visible, when `pressed` has changed since it last set it: one Meshcat
    message per press and per release. (Not at initialization: Drake's visualizer sends its
    objects then, and would put the box's own colour back.)

    Each change is also keyed in Meshcat's recording at the simulation time, so that the
    `--record` replay (`recording.meshcat_html`) shows the presses: as the slip markers',
    the keys are `material.color` of the box's `<object>` (three.js animates a property of
    the object itself; a "color" track names one the scene node lacks; a shell's are its
    `visible`), two a change: the look before it one frame earlier, and the new one (a track
    interpolates between its keys: without the first, the box would fade from one press to
    the next release). With no recording going, the keys go to an animation nobody publishes
    and the next `StartRecording` drops.
    """

    def __init__(self, meshcat, path: str, shell: bool = False):
        super().__init__()
        self._meshcat = meshcat
        self.path = path
        self.shell = shell
        self._pressed = self.DeclareVectorInputPort("pressed", 1)
        self.shown = None
        """Whether the box was last coloured pressed (None: not yet; for tests)."""
        self.DeclarePerStepPublishEvent(self._draw)

    def _draw(self, context) -> None:
        pressed = bool(self._pressed.Eval(context)[0] > 0.5)
        if pressed == self.shown or (self.shown is None and not pressed):
            return
        live, value, target, recorded, keyed = self.looks(pressed)
        self._meshcat.SetProperty(self.path, live, value)
        animation = self._meshcat.get_mutable_recording()
        frame = animation.frame(context.get_time())
        if frame > 0:
            animation.SetProperty(frame - 1, target, recorded, self.looks(not pressed)[4])
        animation.SetProperty(frame, target, recorded, keyed)
        self.shown = pressed

    def looks(self, pressed: bool) -> tuple:
        """(live property, its value, recorded path, recorded property, its value) of the
        look of `pressed`."""
        if self.shell:
            return "visible", pressed, self.path, "visible", pressed
        c = PRESSED_COLOR if pressed else COLOR
        return ("color", [c.r(), c.g(), c.b(), c.a()], f"{self.path}/<object>",
                "material.color", [c.r(), c.g(), c.b()])


# --- the kind ------------------------------------------------------------------------------

BUMPER_SCHEMA = {
    "title": "corobot.Bumper",
    "description": "One bumper sample: pressed, and the contact force on it (N) in its frame "
                   "(+x out of its face), from everything but the ground.",
    "type": "object",
    "properties": {
        "timestamp": {"type": "object", "properties": {
            "sec": {"type": "integer"}, "nsec": {"type": "integer"}}},
        "frame_id": {"type": "string"},
        "pressed": {"type": "boolean"},
        "force": {"type": "number", "description": "N, the force's magnitude"},
        "force_vector": {"type": "object", "description": "N, in frame_id", "properties": {
            "x": {"type": "number"}, "y": {"type": "number"}, "z": {"type": "number"}}},
    },
}
"""The JSON schema of a bumper's Foxglove channel (foxglove-sdk has no contact message)."""


class BumperKind(SensorKind):
    """Bumpers: `robots.<robot>.bumpers.<sensor>` (`BumperConfig`), one `Bumper` each, read as
    a `BumperState` (pressed; N, in the bumper frame; s); topic `bumper/<sensor>`, frame
    `bumper_<sensor>`; ROS 2 geometry_msgs/WrenchStamped, Foxglove JSON (`BUMPER_SCHEMA`)
    (the module docstring says why)."""

    field = "bumpers"
    config_type = BumperConfig
    reading_type = BumperState
    topic = "bumper"
    ros2_type = "geometry_msgs/msg/WrenchStamped"
    ros2_qos = "reliable"  # a press is an event a controller acts on: none may be dropped
    foxglove_schema = BUMPER_SCHEMA
    PRESSED_TOPIC = "pressed"
    """The subtopic of `std_msgs/msg/Bool` pressed, beside the WrenchStamped."""

    def new_sensor(self, name: str) -> BumperConfig:
        return BumperConfig()

    def check(self, config: BumperConfig) -> list[tuple[str, str]]:
        """A `geometry: link` bumper is a link of its robot: not the world (whose geometry
        is the ground and what is welded to it)."""
        frame = config.X_PB.base_frame
        if config.geometry == "link" and (not frame or frame == "world"):
            return [("geometry", "link needs X_PB.base_frame to be a link of the robot; got "
                                 f"{frame or 'none (the world)'}")]
        return []

    def add_geometry(self, plant, model_instance, robot: str, name: str,
                     config: BumperConfig) -> None:
        add_bumper_geometry(plant, model_instance, name, config)

    def log_columns(self, sensor: str) -> tuple[str, ...]:
        """`bumper_<sensor>_pressed` (1 pressed, else 0) and `bumper_<sensor>_force` (N), of
        the latest sample."""
        return (f"bumper_{sensor}_pressed", f"bumper_{sensor}_force")

    def log_port(self, sensor: BuiltSensor):
        return sensor.system.GetOutputPort("sample_state"), (PRESSED, FORCE)

    def add(self, site, name: str, config: BumperConfig) -> BuiltSensor | None:
        """The bumper `name` on the site's robot (`<robot>.bumper.<name>`), fed by SceneGraph's
        queries and the plant's contact results and body poses; its vector outputs exported as
        `<robot>.bumper.<name>.<port>`."""
        if not config.enabled:
            return None
        plant, builder, robot = site.plant, site.builder, site.robot
        body, X_BS = mount_frame(plant, site.model_instance, config.X_PB)
        ground = ground_geometries(plant, site.scene_graph)
        if config.geometry == "link":
            geometries = link_geometries(plant, body, ground)
            extra = {"geometries": geometries, "body": body.index(),
                     "body_poses": plant.get_body_poses_output_port(),
                     "scene_graph": site.scene_graph}
        else:
            collision, visual = bumper_geometries(plant, site.scene_graph, body, name)
            geometries = {collision}
            extra = {"meshcat_path": meshcat_path(site.scene_graph, visual)}
        sensor = builder.AddNamedSystem(f"{robot}.bumper.{name}", Bumper(
            config, geometries, ground, body.index(), X_BS, site.continuous_step))
        builder.Connect(site.scene_graph.get_query_output_port(),
                        sensor.GetInputPort("query_object"))
        builder.Connect(plant.get_contact_results_output_port(),
                        sensor.GetInputPort("contact_results"))
        builder.Connect(plant.get_body_poses_output_port(), sensor.GetInputPort("body_poses"))
        for i in range(1, sensor.num_output_ports()):  # the vectors (0: the abstract reading)
            port = sensor.get_output_port(i)
            builder.ExportOutput(port, f"{robot}.bumper.{name}.{port.get_name()}")
        return BuiltSensor(self, robot, name, config, sensor, sensor.GetOutputPort("reading"),
                           sensor.rate, config.X_PB, extra)

    def add_meshcat(self, builder, meshcat, sensor: BuiltSensor) -> None:
        """Its box red while pressed; a `geometry: link` bumper's shell under
        `/bumper/<robot>/<bumper>` (`draw_shell`), moved with its link, shown while pressed."""
        extra, name = sensor.extra, f"{sensor.robot}.bumper.{sensor.name}"
        if "geometries" in extra:
            path = f"/bumper/{sensor.robot}/{sensor.name}"
            draw_shell(meshcat, path, extra["scene_graph"], extra["geometries"])
            follow = builder.AddNamedSystem(f"{name}.follow", FollowFrame(
                meshcat, path, extra["body"], RigidTransform()))
            builder.Connect(extra["body_poses"], follow.get_input_port())
            viz = builder.AddNamedSystem(f"{name}.meshcat", BumperMeshcat(meshcat, path, True))
        else:
            viz = builder.AddNamedSystem(f"{name}.meshcat",
                                         BumperMeshcat(meshcat, extra["meshcat_path"]))
        builder.Connect(sensor.system.GetOutputPort("pressed"), viz.get_input_port())

    def looks(self, sensor: BuiltSensor) -> tuple[float, float]:
        return sensor.system.events  # a sample and a look at one time: the look first

    def foxglove_message(self, reading: BumperState, frame: str) -> dict:
        """The reading as `BUMPER_SCHEMA` (JSON)."""
        ns = nanoseconds(reading.time) if math.isfinite(reading.time) else 0
        return {"timestamp": {"sec": ns // 1_000_000_000, "nsec": ns % 1_000_000_000},
                "frame_id": frame, "pressed": reading.pressed, "force": reading.force,
                "force_vector": dict(zip("xyz", reading.force_vector, strict=True))}

    def ros2_channels(self) -> dict:
        """`bumper/<sensor>` (the WrenchStamped) and `bumper/<sensor>/pressed` (Bool), both
        reliable, both with every sample (module docstring)."""
        return {"": (self.ros2_type, self.ros2_qos),
                self.PRESSED_TOPIC: ("std_msgs/msg/Bool", self.ros2_qos)}

    def ros2_message(self, messages, reading: BumperState, frame: str) -> dict:
        T = messages.T
        return {"": T["geometry_msgs/msg/WrenchStamped"](
                    header=messages.header(reading.time, frame),
                    wrench=T["geometry_msgs/msg/Wrench"](
                        force=messages.vector3(reading.force_vector),
                        torque=messages.vector3((0.0, 0.0, 0.0)))),
                self.PRESSED_TOPIC: T["std_msgs/msg/Bool"](data=reading.pressed)}


BUMPER = BumperKind()
"""The kind's one instance (`sensors/registry.KINDS`)."""
