"""A hostile corpus of scenario inputs and what the loader makes of each (tools/hostile_inputs.py,
tests/packaging/test_hostile_inputs.py).

Every input here is invalid, and must end in one line `FILE_OR_--override[:LINE]: FIELD:
MESSAGE` (the CLI prints it after `error: ` and exits 2) within 2 s of CPU time, before
anything is built: `HAND_WRITTEN` (YAML text or bytes -> the field and a fragment of the
message) and, generated, hostile values put into every numeric field of the shipped scenarios
(`mutated_override`) and edits of their text (`mutated_file`). A mutation's choices come from
a `draw`: `RandomDraw` (seeded) in the tool, hypothesis in the test (a dev dependency).

`ros_requests`: the ROS 2 node's bad Simulation Interfaces requests, each with the result code
and the words of the one line it must get (tests/service/test_ros2_simulation.py asks them).
"""

from __future__ import annotations

import copy
import dataclasses as dc
import functools
import json
import math
import os
import random
import re
import threading
import time
from pathlib import Path

from corobot_drake.config.scenario import ScenarioError, load_scenario
from corobot_drake.resources import DEFAULT_SCENARIO, SCENARIOS_DIR

CPU_SECONDS = 2.0
"""The most CPU time one bad input may take to be refused."""
HANG_SECONDS = 60.0
"""Wall-clock seconds after which a load counts as hung (the host may be loaded)."""

ERROR_LINE = re.compile(r"^(?P<source>.+?)(?::(?P<line>\d+))?: (?P<field>.+?): (?P<message>\S.*)$")
"""The one line of a ScenarioError (the CLI prefixes `error: `)."""


@dc.dataclass(frozen=True)
class Case:
    """One bad input: YAML `text` (an --override), or the `data` of a file, or a `path` to
    read; the `field` the error must name and `words` its message must contain."""

    name: str
    field: str
    words: str
    text: str | None = None
    data: bytes | None = None
    path: str | None = None
    line: int | None = 1
    """The line the error must name (None: a file that cannot be read names none)."""
    files: tuple = ()
    """(name, bytes or a size) of files written beside the scenario file (a robot file and its
    model); a size makes a sparse file of that many bytes (a huge mesh, on no disk)."""
    blame: str | None = None
    """The file beside the scenario that the error must name (a robot file), if not it."""


@dc.dataclass
class Outcome:
    """What loading one input gave."""

    error: str | None = None
    """The ScenarioError's line; None when the input was accepted or failed otherwise."""
    other: str | None = None
    """Any other exception (a defect), as `Type: message`."""
    cpu_seconds: float = 0.0
    hung: bool = False

    def match(self):
        return ERROR_LINE.match(self.error) if self.error else None


def load(path: str | Path | None = None, overrides: tuple[str, ...] = ()) -> Outcome:
    """Loads a scenario file (default: the default scenario, loaded once) with `overrides`
    in a thread of its own, so that a hang is reported (`hung`) instead of hanging the
    caller."""
    outcome = Outcome()
    defaults = copy.deepcopy(_default_scenario()) if path is None else None

    def run():
        start = time.thread_time()
        try:
            load_scenario(path if defaults is None else None, overrides=list(overrides),
                          defaults=defaults)
        except ScenarioError as e:
            outcome.error = str(e)
        except BaseException as e:  # a defect to report, whatever it is
            outcome.other = f"{type(e).__name__}: {str(e)[:200]}"
        outcome.cpu_seconds = time.thread_time() - start

    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    thread.join(HANG_SECONDS)
    outcome.hung = thread.is_alive()
    return outcome


@functools.cache
def _default_scenario():
    return load_scenario(DEFAULT_SCENARIO)


def problems(outcome: Outcome, source: str, field: str | None = None, words: str = "",
             line: int | None = None) -> list[str]:
    """What is wrong with an outcome of a bad input (empty: the one clear line, in time).
    `field` None: any field; `line` None: any line or none."""
    found = []
    if outcome.hung:
        return [f"hung (more than {HANG_SECONDS:g} s)"]
    if outcome.other:
        found.append(f"not a ScenarioError: {outcome.other}")
    elif outcome.error is None:
        found.append("accepted")
    elif "\n" in outcome.error or not outcome.match():
        found.append(f"not one line FILE[:LINE]: FIELD: MESSAGE: {outcome.error!r}")
    else:
        m = outcome.match()
        if m["source"] != source:
            found.append(f"blames {m['source']!r}, not {source!r}")
        if field is not None and m["field"] != field:
            found.append(f"names field {m['field']!r}, not {field!r}")
        if line is not None and m["line"] != str(line):
            found.append(f"names line {m['line']}, not {line}")
        if words not in m["message"]:
            found.append(f"message {m['message']!r} lacks {words!r}")
    if outcome.cpu_seconds > CPU_SECONDS:
        found.append(f"took {outcome.cpu_seconds:.2f} s of CPU time (> {CPU_SECONDS:g})")
    return found


# --- the hand-written corpus ----------------------------------------------------------------


def _override(name: str, text: str, field: str, words: str) -> Case:
    return Case(name, field, words, text=text)


def _robot(name: str, yaml: str, field: str, words: str) -> Case:
    return _override(name, f"robots: {{corobot: {yaml}}}", f"robots.corobot.{field}", words)


def _body(name: str, yaml: str, field: str, words: str) -> Case:
    return _override(name, f"world: {{bodies: {{giant_box: {yaml}}}}}",
                     f"world.bodies.giant_box.{field}", words)


def _camera(name: str, yaml: str, field: str, words: str) -> Case:
    return _robot(name, f"{{cameras: {{front: {yaml}}}}}", f"cameras.front.{field}", words)


def _ir(name: str, yaml: str, field: str, words: str) -> Case:
    return _robot(name, f"{{ir_sensors: {{front: {yaml}}}}}", f"ir_sensors.front.{field}",
                  words)


def _lidar(name: str, yaml: str, field: str, words: str) -> Case:
    return _robot(name, f"{{lidars: {{top: {yaml}}}}}", f"lidars.top.{field}", words)


def _bumper(name: str, yaml: str, field: str, words: str) -> Case:
    return _robot(name, f"{{bumpers: {{bump: {yaml}}}}}", f"bumpers.bump.{field}", words)


def _imu(name: str, yaml: str, field: str, words: str) -> Case:
    return _robot(name, f"{{imus: {{imu: {yaml}}}}}", f"imus.imu.{field}", words)


def _file(name: str, data: bytes, field: str, words: str, line: int | None = 1) -> Case:
    return Case(name, field, words, data=data, line=line)


TOP = "(top level)"
STEP = "plant_config.time_step"

# --- robot files: a scenario naming a bad robot file, blamed at the robot file's line ------

_LINK = ('<link name="{name}"><inertial><origin xyz="{com}"/><mass value="{mass}"/>'
         '<inertia ixx="{i}" iyy="{i}" izz="{i}" ixy="0" ixz="0" iyz="0"/></inertial>'
         '{shape}</link>')
_TYRE = ('<collision><origin rpy="1.5707963267948966 0 0"/><geometry>'
         '<cylinder radius="{r}" length="0.02"/></geometry></collision>')
_CASTER = ('<collision name="caster"><origin xyz="-0.06 0 0.01"/><geometry>'
           '<sphere radius="0.01"/></geometry></collision>')
_JOINT = ('<joint name="{name}_joint" type="{type}"><parent link="base_link"/>'
          '<child link="{name}"/><origin xyz="{x} {y} {z}"/><axis xyz="0 1 0"/></joint>')


def _urdf(wheels=(("left", 0.0, 0.08, 0.033), ("right", 0.0, -0.08, 0.033)),
          joint: str = "continuous", base_mass: float = 1.0, base_inertia: float = 0.01,
          extra: str = "") -> bytes:
    """A small robot's URDF: a base with a rear ball caster, `wheels` (name, x, y, radius)
    standing on the ground on `joint` joints."""
    links = [_LINK.format(name="base_link", com="-0.03 0 0.06", mass=base_mass,
                          i=base_inertia, shape=_CASTER + extra)]
    for name, x, y, r in wheels:
        links.append(_LINK.format(name=name, com="0 0 0", mass=0.05, i=2e-5,
                                  shape=_TYRE.format(r=r)))
        links.append(_JOINT.format(name=name, type=joint, x=x, y=y, z=r))
    return f'<?xml version="1.0"?>\n<robot name="small">{"".join(links)}</robot>\n'.encode()


_ROBOT_YAML = ("model: small.urdf\nbase: base_link\n"
               "wheels: {left: [left_joint], right: [right_joint]}\ndrive: {top_speed: 0.2}\n")


def _robot_file(name: str, field: str, words: str, line: int, robot_yaml: str = _ROBOT_YAML,
                urdf: bytes | None = None, files: tuple = ()) -> Case:
    """A scenario whose robot `r` is the robot file `robot_yaml` (beside it, with the model
    `urdf` as small.urdf and `files`): the error names the robot file's `field` at `line`."""
    return Case(f"robot file: {name}", field, words, line=line,
                data=b"robots:\n  r: {robot: robot.yaml}\n", blame="robot.yaml",
                files=(("robot.yaml", robot_yaml.encode()), ("small.urdf", urdf or _urdf()),
                       *files))


def _with(line: str, replacement: str) -> str:
    """`_ROBOT_YAML` with its line starting `line` replaced."""
    return "".join(replacement + "\n" if row.startswith(line) else row + "\n"
                   for row in _ROBOT_YAML.splitlines())


_SELF_SDF = (b'<?xml version="1.0"?>\n<sdf version="1.9"><model name="selfie"><link name="b"/>'
             b"<include><uri>self.sdf</uri><name>again</name></include></model></sdf>\n")

ROBOT_FILES = [
    _robot_file("model does not parse", "model", "Drake's parser cannot read", 1,
                urdf=b'<robot name="x"><link name="a">\n'),
    _robot_file("model missing", "model", "cannot read the file", 1,
                _with("model:", "model: gone.urdf")),
    _robot_file("model not a model", "model", "a model is a URDF", 1,
                _with("model:", "model: small.txt")),
    _robot_file("base not a link", "base", "no link 'chassis'", 2,
                _with("base:", "base: chassis")),
    _robot_file("wheel joint missing", "wheels.right[0]", "no joint 'rite_joint'", 3,
                _with("wheels:", "wheels: {left: [left_joint], right: [rite_joint]}")),
    _robot_file("wheel joint not revolute", "wheels.left[0]", "a weld joint", 3,
                urdf=_urdf(joint="fixed")),
    _robot_file("wheels on one side", "wheels.right", "at least one wheel joint on each", 3,
                _with("wheels:", "wheels: {left: [left_joint]}")),
    _robot_file("wheel off the ground", "wheels.left[0]", "does not touch the ground", 3,
                urdf=_urdf((("left", 0.0, 0.08, 0.033), ("right", 0.0, -0.08, 0.033)))
                .replace(b'xyz="0.0 0.08 0.033"', b'xyz="0.0 0.08 0.05"')),
    _robot_file("unequal radii on a side", "wheels.left", "one radius", 3,
                _with("wheels:", "wheels: {left: [left_joint, back_left_joint], "
                      "right: [right_joint]}"),
                urdf=_urdf((("left", 0.05, 0.08, 0.033), ("back_left", -0.05, 0.08, 0.04),
                            ("right", 0.0, -0.08, 0.033)))),
    _robot_file("stated radius disagrees", "wheels.radius", "measure", 3,
                _with("wheels:", "wheels: {left: [left_joint], right: [right_joint], "
                      "radius: 0.05}")),
    _robot_file("no mass", "model", "no mass", 1, urdf=_urdf(base_mass=0.0, base_inertia=0.0)),
    _robot_file("degenerate inertia", "model", "degenerate inertia", 1,
                urdf=_urdf(base_inertia=-1.0)),
    _robot_file("no mass but an inertia", "model", "a link has no mass", 1,
                urdf=_urdf(base_mass=0.0)),
    _robot_file("point-mass base", "model", "no rotational inertia", 1,
                urdf=_urdf(base_inertia=0.0)),
    _robot_file("chassis 1 cm into the ground", "model", "goes 10 mm into the ground", 1,
                urdf=_urdf(extra='<collision><origin xyz="0 0 0.02"/><geometry>'
                                 '<box size="0.1 0.1 0.06"/></geometry></collision>')),
    _robot_file("a 1e9 m box", "model", "into the ground", 1,
                urdf=_urdf(extra='<collision><geometry><box size="1e9 1e9 1e9"/></geometry>'
                                 "</collision>")),
    _robot_file("sensor on an unknown link", "lidars.scan.X_PB.base_frame", "not a link", 5,
                _ROBOT_YAML + "lidars: {scan: {X_PB: {base_frame: mast}}}\n"),
    _robot_file("no drive speed", "drive", "needs one of top_speed", 4,
                _with("drive:", "drive: {slew_rate: 10}")),
    _robot_file("model includes itself", "model", "includes itself", 1,
                _with("model:", "model: self.sdf"), files=(("self.sdf", _SELF_SDF),)),
    _robot_file("huge mesh", "model", "a robot's mesh may be at most", 1,
                urdf=_urdf(extra='<visual><geometry><mesh filename="huge.obj"/></geometry>'
                                 "</visual>"),
                files=(("huge.obj", 40 << 20),)),
    _robot_file("mesh just over the limit", "model", "is 32.1 MiB; a robot's mesh may be at "
                "most 32 MiB", 1,
                urdf=_urdf(extra='<visual><geometry><mesh filename="big.obj"/></geometry>'
                                 "</visual>"),
                files=(("big.obj", (32 << 20) + 1),)),
    _robot_file("unknown field", "wheels.lefty", "", 3,
                _with("wheels:", "wheels: {lefty: [left_joint], right: [right_joint]}")),
    Case("robot file: missing", "robots.r.robot", "neither a shipped robot", line=2,
         data=b"robots:\n  r: {robot: nowhere.yaml}\n"),
]

FILES = [
    _file("non-UTF-8", b"robots:\n  corobot:\n    \xff\xfe: 1\n", TOP, "not UTF-8", 3),
    _file("UTF-16", "robots: {}\n".encode("utf-16"), TOP, "not UTF-8", 1),
    _file("Latin-1 name", b"robots:\n  caf\xe9: {}\n", TOP, "not UTF-8", 2),
    _file("empty", b"", TOP, "empty"),
    _file("only a comment", b"# nothing here\n", TOP, "empty"),
    _file("only blank lines", b"\n\n\n", TOP, "empty"),
    _file("flow nested 5000 deep", b"robots: " + b"[" * 5000 + b"]" * 5000, TOP,
          "nested deeper than 64"),
    _file("flow nested 100000 deep", b"[" * 100_000, TOP, "nested deeper than 64"),
    _file("block nested 200 deep", "".join(f"{' ' * i}a:\n" for i in range(200)).encode(),
          TOP, "nested deeper than 64", 65),
    _file("over 256 KiB", b"# " + b"x" * (256 << 10) + b"\n", TOP, "larger than 256 KiB", None),
    _file("25k values", b"robots: {corobot: {wheel_angles: [" + b"0," * 25_000 + b"0]}}",
          TOP, "more than 20000 values"),
    _file("NUL character", b"robots:\n  corobot: {}\n  \x00: 1\n", TOP,
          "not valid YAML: character '\\x00'", 3),
    _file("two documents", b"robots: {}\n---\nrobots: {}\n", TOP, "not valid YAML", 2),
    _file("tab indentation", b"robots:\n\tcorobot: {}\n", TOP, "not valid YAML", 2),
    _file("tab after a key", b"world:\n  sky_color:\t [0.5, 0.5, 0.5]\n", TOP,
          "not valid YAML: found character '\\t' that cannot start any token", 2),
    _file("unclosed bracket", b"robots: [\n", TOP, "not valid YAML", 2),
    _file("a list", b"- robots\n", TOP, "expected a mapping for Scenario"),
    _file("a number", b"42\n", TOP, "expected a mapping for Scenario"),
    _file("recursive alias", b"robots: &r {corobot: *r}\n", TOP, "nested deeper than 64"),
    _file("field on line 6", b"# a scenario\nworld:\n  ground:\n    friction: 0.5\n"
          b"  sun:\n    direction: [0, 0, 0]\n", "world.sun.direction", "must not be zero", 6),
    _file("step on line 3", b"plant_config:\n  discrete_contact_approximation: lagged\n"
          b"  time_step: 1.0\n", STEP, "or in [0.0001, 0.02] s", 3),
    _file("robot in the ground, line 5", b"robots:\n  corobot:\n    drive: {}\n"
          b"    # half a metre down\n    pose: {translation: [0, 0, -0.5]}\n",
          "robots.corobot.pose", "below the ground", 5),
    _file("command on line 7", b"robots:\n  corobot:\n    commands:\n"
          b"      - !SetPower {left: 0.5, right: 0.5}\n      - !Wait {seconds: 1}\n"
          b"      - !Wait\n        seconds: -1\n", "robots.corobot.commands[2].seconds",
          "must be in [0, 1e+07] s", 7),
]

READS = [
    Case("directory", TOP, "cannot read a directory", path="{tmp}", line=None),
    Case("/dev/zero", TOP, "cannot read a device", path="/dev/zero", line=None),
    Case("/dev/null", TOP, "cannot read a device", path="/dev/null", line=None),
    Case("FIFO", TOP, "cannot read a FIFO", path="{fifo}", line=None),
    Case("missing", TOP, "cannot read the file", path="{tmp}/nowhere.yaml", line=None),
]

OVERRIDES = [
    # the plant and the simulator
    _override("step 1e-7", "plant_config: {time_step: 1e-7}", STEP, "[0.0001, 0.02] s"),
    _override("step 1 s", "plant_config: {time_step: 1.0}", STEP, "[0.0001, 0.02] s"),
    _override("a continuous plant without CENIC",
              "simulator_config: {integration_scheme: runge_kutta3}",
              "simulator_config.integration_scheme", "needs cenic"),
    _override("CENIC on a discrete plant", "plant_config: {time_step: 0.01}", STEP,
              "cenic needs a continuous plant"),
    _override("CENIC step 1 s", "simulator_config: {max_step_size: 1.0}",
              "simulator_config.max_step_size", "[0.0001, 0.02] s"),
    _override("CENIC solver tolerance 0", "cenic_solver: {min_tolerance: 0.0}",
              "cenic_solver.min_tolerance", "(0, 1e-05]"),
    _override("CENIC solver iterations past Drake's int", "cenic_solver: {max_iterations: "
              "2147483648}", "cenic_solver.max_iterations", "(Drake's int)"),
    _override("CENIC solver under SAP",
              "{plant_config: {time_step: 0.01}, simulator_config: {integration_scheme: "
              "runge_kutta3}, cenic_solver: {max_iterations: 50}}", "cenic_solver",
              "only with integration_scheme: cenic"),
    _override("step negative", "plant_config: {time_step: -0.01}", STEP, "got -0.01"),
    _override("step inf", "plant_config: {time_step: .inf}", STEP, "got inf"),
    _override("step 1e300", "plant_config: {time_step: 1e300}", STEP, "got 1e+300"),
    _override("step NaN", "plant_config: {time_step: .nan}", STEP, "NaN is not allowed"),
    _override("step text", "plant_config: {time_step: fast}", STEP, "expected a number"),
    _override("tamsi", "plant_config: {discrete_contact_approximation: tamsi}",
              "plant_config.discrete_contact_approximation", "ignores the wheels'"),
    _override("contact model", "plant_config: {contact_model: soft}",
              "plant_config.contact_model", "not one of hydroelastic, point"),
    _override("penetration allowance", "plant_config: {penetration_allowance: -1}",
              "plant_config.penetration_allowance", "(0, 0.1] m"),
    _override("stiction", "plant_config: {stiction_tolerance: 0}",
              "plant_config.stiction_tolerance", "(0, 1] m/s"),
    _override("surface", "plant_config: {contact_surface_representation: quads}",
              "plant_config.contact_surface_representation", "not one of polygon, triangle"),
    _override("integrator", "simulator_config: {integration_scheme: magic}",
              "simulator_config.integration_scheme", "not one of bogacki_shampine3"),
    _override("start -5", "simulator_config: {start_time: -5}", "simulator_config.start_time",
              "[0, 1e+07] s"),
    _override("start inf", "simulator_config: {start_time: .inf}",
              "simulator_config.start_time", "got inf"),
    _override("start 1e300", "simulator_config: {start_time: 1e300}",
              "simulator_config.start_time", "got 1e+300"),
    _override("accuracy", "simulator_config: {accuracy: 0}", "simulator_config.accuracy",
              "(0, 1]"),
    _override("max step", "simulator_config: {max_step_size: -1}",
              "simulator_config.max_step_size", "(0, 1] s"),
    _override("realtime rate", "simulator_config: {target_realtime_rate: -1}",
              "simulator_config.target_realtime_rate", "[0, 1000]"),
    _override("duration -3", "simulation_duration: -3", "simulation_duration", "> 0 s, or .inf"),
    _override("duration 0", "simulation_duration: 0", "simulation_duration", "got 0"),
    _override("seed huge", "random_seed: 99999999999999", "random_seed", "Drake's int"),
    _override("seed float", "random_seed: 1.5", "random_seed", "expected an integer"),
    _override("seed 1e99", "random_seed: 1e99", "random_seed", "expected an integer"),
    _override("empty override", "", TOP, "empty"),
    _override("unknown top field", "robot: {}", "robot", "unknown field; Scenario has"),
    _override("robots a list", "robots: [corobot]", "robots", "expected a mapping of names"),
    _override("duplicate robot", "robots: {a: {}, a: {}}", "robots.a", "duplicate name"),
    # the world
    _override("ground friction", "world: {ground: {friction: -1}}", "world.ground.friction",
              "[0, 10] (Coulomb friction"),
    _override("ground friction inf", "world: {ground: {friction: .inf}}",
              "world.ground.friction", "got inf"),
    _override("ground colour", "world: {ground: {color: [2, 0, 0, 1]}}",
              "world.ground.color[0]", "[0, 1] (a colour component)"),
    _override("ground colour size", "world: {ground: {color: [0, 0, 0]}}",
              "world.ground.color", "needs 4 numbers, got 3"),
    _override("sun zero", "world: {sun: {direction: [0, 0, 0]}}", "world.sun.direction",
              "must not be zero"),
    _override("sun size", "world: {sun: {direction: [1, 2]}}", "world.sun.direction",
              "needs 3 numbers"),
    _override("sun intensity", "world: {sun: {intensity: -1}}", "world.sun.intensity",
              "[0, 100]"),
    _override("sky", "world: {sky_color: [1.5, 0, 0]}", "world.sky_color[0]", "[0, 1]"),
    _body("box size 0", "{shape: !Box {size: [0, 1, 1]}}", "shape.size[0]",
          "[0.001, 100] m (a shape's dimensions)"),
    _body("box size negative", "{shape: !Box {size: [1, -1, 1]}}", "shape.size[1]", "got -1"),
    _body("box size inf", "{shape: !Box {size: [1, 1, .inf]}}", "shape.size[2]", "got inf"),
    _body("box size 1e9", "{shape: !Box {size: [1e9, 1, 1]}}", "shape.size[0]", "got 1e+09"),
    _body("box size short", "{shape: !Box {size: [1, 1]}}", "shape.size", "needs 3 numbers"),
    _body("sphere 0", "{shape: !Sphere {radius: 0}}", "shape.radius", "[0.001, 100] m"),
    _body("cylinder", "{shape: !Cylinder {length: -1}}", "shape.length", "got -1"),
    _body("capsule inf", "{shape: !Capsule {radius: .inf}}", "shape.radius", "got inf"),
    _body("ellipsoid 0", "{shape: !Ellipsoid {a: 0}}", "shape.a", "got 0"),
    _body("ellipsoid a needle", "{shape: !Ellipsoid {a: 1, b: 0.05, c: 0.05}}", "shape",
          "at most 4 times its smallest"),
    _body("unknown shape", "{shape: !Torus {}}", "shape", "unknown tag !Torus"),
    _body("mass inf", "{mass: .inf}", "mass", "[0.001, 100000] kg"),
    _body("mass 1e-300", "{mass: 1e-300}", "mass", "got 1e-300"),
    _body("mass 0", "{mass: 0}", "mass", "got 0"),
    _body("mass negative", "{mass: -100}", "mass", "got -100"),
    _body("body at 1e6 m/s", "{velocity: [0, 0, 0, 1e6, 0, 0]}", "velocity[3]",
          "[-50, 50] m/s"),
    _body("body spinning", "{velocity: [1e3, 0, 0, 0, 0, 0]}", "velocity[0]",
          "[-100, 100] rad/s"),
    _body("velocity short", "{velocity: [0, 0, 0, 0, 0]}", "velocity", "needs 6 numbers"),
    _body("body friction", "{friction: -0.5}", "friction", "[0, 10]"),
    _body("modulus 1e30", "{hydroelastic_modulus: 1e30}", "hydroelastic_modulus",
          "0 (rigid) or in [10000, 1e+11] Pa"),
    _body("modulus negative", "{hydroelastic_modulus: -1}", "hydroelastic_modulus", "got -1"),
    _body("modulus 1 Pa", "{hydroelastic_modulus: 1}", "hydroelastic_modulus", "got 1"),
    _body("body colour", "{color: [0, 0, 0, 2]}", "color[3]", "[0, 1]"),
    _body("body at -inf", "{pose: {translation: [0, 0, -.inf]}}", "pose.translation[2]",
          "got -inf"),
    _body("body far away", "{pose: {translation: [1e9, 0, 0]}}", "pose.translation[0]",
          "[-10000, 10000] m"),
    _body("zero axis", "{pose: {rotation: !AngleAxis {angle_deg: 90, axis: [0, 0, 0]}}}",
          "pose.rotation", "non-zero axis"),
    _body("random pose", "{pose: {translation: !UniformVector {min: [0, 0, 0], "
          "max: [1, 1, 1]}}}", "pose", "must be a fixed pose"),
    _body("body base frame", "{pose: {base_frame: corobot}}", "pose.base_frame",
          "has no base_frame"),
    _body("box in the ground", "{pose: {translation: [-1.7366, 0, -5]}}", "pose",
          "below the ground"),
    _body("box on the robot", "{pose: {translation: [0, 0, 1.0]}}", "pose",
          "inside world body 'giant_box'"),
    _body("rpy inf", "{pose: {rotation: !Rpy {deg: [.inf, 0, 0]}}}", "pose.rotation.deg[0]",
          "[-1e+06, 1e+06] deg; got inf"),
    # the robots
    _robot("below the ground", "{pose: {translation: [0, 0, -0.5]}}", "pose",
           "mm below the ground (at most 5 mm allowed); lift it"),
    _robot("upside down", "{pose: {rotation: !Rpy {deg: [180, 0, 0]}}}", "pose",
           "below the ground"),
    _robot("inside the box", "{pose: {translation: [-1.5, 0, 0]}}", "pose",
           "inside world body 'giant_box'"),
    _robot("far away", "{pose: {translation: [1e5, 0, 0]}}", "pose.translation[0]",
           "[-10000, 10000] m"),
    _override("robots overlap", "robots: {second: {pose: {translation: [0.1, 0, 0]}}}",
              "robots.second.pose", "inside robot 'corobot'"),
    _override("robot named like a body", "robots: {giant_box: {pose: {translation: [2, 0, 0]}}}",
              "robots.giant_box", "a world body already has this name"),
    _override("robot name with ::", "robots: {'a::b': {pose: {translation: [2, 0, 0]}}}",
              "robots.a::b", "a URL path segment"),
    _robot("wheel speed 1e9", "{wheel_speeds: [1e9, 0, 0, 0]}", "wheel_speeds[0]",
           "[-200, 200] rad/s"),
    _robot("wheel speeds short", "{wheel_speeds: [0, 0]}", "wheel_speeds", "needs 4 numbers"),
    _robot("axle command 1e300", "{axle_speed_command: [1e300, -1e300]}",
           "axle_speed_command[0]", "[-200, 200] rad/s; got 1e+300"),
    _robot("resumed drive's start far", "{commands: [!DriveDistance {distance: 1, "
           "start: [0, 0, 1e9]}]}", "commands[0].start[2]", "[-3600, 3600] deg"),
    _robot("wheel angle inf", "{wheel_angles: [.inf, 0, 0, 0]}", "wheel_angles[0]", "got inf"),
    _robot("robot at 1e6 m/s", "{velocity: [0, 0, 0, 1e6, 0, 0]}", "velocity[3]",
           "[-50, 50] m/s"),
    _robot("velocity text", "{velocity: fast}", "velocity", "expected a list"),
    _robot("torque scaling 0", "{drive: {motor_torque_scaling: 0}}",
           "drive.motor_torque_scaling", "(0, 200] rad/s"),
    _robot("torque scaling 1e9", "{drive: {motor_torque_scaling: 1e9}}",
           "drive.motor_torque_scaling", "got 1e+09"),
    _robot("slew negative", "{drive: {slew_rate: -1}}", "drive.slew_rate",
           "(0, 10000] rad/s^2"),
    _robot("slew list", "{drive: {slew_rate: [1, 2]}}", "drive.slew_rate",
           "expected a number, got a list"),
    _robot("axle speed inf", "{drive: {max_axle_speed: .inf}}", "drive.max_axle_speed",
           "got inf"),
    _robot("control 1e-7", "{drive: {control_period: 1e-7}}", "drive.control_period",
           "[0.001, 1] s"),
    _robot("control inf", "{drive: {control_period: .inf}}", "drive.control_period", "got inf"),
    _robot("control 0", "{drive: {control_period: 0}}", "drive.control_period", "got 0"),
    _robot("tyre friction", "{contact: {friction: -0.1}}", "contact.friction", "[0, 10]"),
    _robot("tyre modulus 1e30", "{contact: {hydroelastic_modulus: 1e30}}",
           "contact.hydroelastic_modulus", "[100000, 1e+08] Pa"),
    _robot("tyre modulus 10", "{contact: {hydroelastic_modulus: 10}}",
           "contact.hydroelastic_modulus", "got 10"),
    _robot("resolution 1e-6", "{contact: {resolution_hint: 1e-6}}", "contact.resolution_hint",
           "[0.001, 0.02] m"),
    _robot("resolution 1 m", "{contact: {resolution_hint: 1}}", "contact.resolution_hint",
           "got 1"),
    _robot("dissipation", "{contact: {hunt_crossley_dissipation: -1}}",
           "contact.hunt_crossley_dissipation", "[0, 100] s/m"),
    _robot("effort 0", "{contact: {effort_limit: 0}}", "contact.effort_limit", "(0, 1000] N m"),
    _robot("damping 1e9", "{contact: {servo_damping: 1e9}}", "contact.servo_damping",
           "(0, 1000] N m s/rad"),
    _robot("visual", "{visual: sketch}", "visual", "not one of meshes, boxes"),
    _robot("profile", "{motion: {profile: fast}}", "motion.profile",
           "not one of closed_loop, seed"),
    _robot("stall time", "{motion: {stall_time: 0}}", "motion.stall_time", "(0, 1000] s"),
    _robot("unknown field", "{colour: red}", "colour", "unknown field; Robot has"),
    # commands
    _robot("power inf", "{commands: [!SetPower {left: .inf, right: 0}]}", "commands[0].left",
           "must be in [-1, 1]; got inf"),
    _robot("speed -inf", "{commands: [!SetSpeed {left: 0, right: -.inf}]}",
           "commands[0].right", "got -inf"),
    _robot("power text", "{commands: [!SetPower {left: fast}]}", "commands[0].left",
           "expected a number, got 'fast'"),
    _robot("wait negative", "{commands: [!Wait {seconds: -1}]}", "commands[0].seconds",
           "[0, 1e+07] s"),
    _robot("wait inf", "{commands: [!Wait {seconds: .inf}]}", "commands[0].seconds", "got inf"),
    _robot("drive power 0", "{commands: [!DriveDistance {distance: 1, power: 0}]}",
           "commands[0].power", "(0, 1]"),
    _robot("drive power 2", "{commands: [!DriveDistance {distance: 1, power: 2}]}",
           "commands[0].power", "got 2"),
    _robot("drive 1e9 m", "{commands: [!DriveDistance {distance: 1e9}]}",
           "commands[0].distance", "[-100, 100] m"),
    _robot("rotate inf", "{commands: [!RotateDegrees {degrees: .inf}]}", "commands[0].degrees",
           "got inf"),
    _robot("set pose far", "{commands: [!SetPose {x: 1e300}]}", "commands[0].x",
           "[-10000, 10000] m"),
    _robot("unknown command", "{commands: [!Fly {}]}", "commands[0]", "unknown tag !Fly"),
    _robot("command untagged", "{commands: [5]}", "commands[0]", "expected a mapping"),
    # the camera
    _robot("old camera key", "{camera: {rgb: false}}", "camera",
           "replaced by `cameras`, a map of cameras by name: write `cameras: {front: {...}}`"),
    _robot("camera name with a slash", "{cameras: {a/b: {}}}", "cameras.a/b",
           "a sensor name must be letters, digits"),
    _camera("width -1", "{width: -1}", "width", "[1, 4096] pixels; got -1"),
    _camera("100000 square", "{width: 100000, height: 100000}", "width", "got 100000"),
    _camera("height 0", "{height: 0}", "height", "got 0"),
    _camera("fps 0", "{fps: 0}", "fps", "(0, 240] Hz"),
    _camera("fps 1e9", "{fps: 1e9}", "fps", "got 1e+09"),
    _camera("delay a frame", "{output_delay: 0.5}", "output_delay", "less than one frame"),
    _camera("fov 0", "{focal: !FovDegrees {y: 0}}", "focal.y", "(0, 180) deg"),
    _camera("fov 200", "{focal: !FovDegrees {x: 200}}", "focal.x", "got 200"),
    _camera("focal negative", "{focal: !FocalLength {x: -1}}", "focal.x", "(0, 1e+06] pixels"),
    _camera("near 0", "{clipping_near: 0}", "clipping_near", "(0, 1000] m"),
    _camera("far before near", "{clipping_near: 2, clipping_far: 1}", "clipping_far",
            "must be more than clipping_near"),
    _camera("background", "{background: {rgba: [2, 0, 0, 1]}}", "background.rgba[0]",
            "[0, 1]"),
    _camera("depth", "{depth: true}", "depth", "only the colour image"),
    _camera("renderer", "{renderer_class: Blender}", "renderer_class",
            "must be RenderEngineGl, RenderEngineVtk"),
    _camera("center negative", "{center_x: -5}", "center_x", "(0, 4096] pixels"),
    _camera("capture offset", "{capture_offset: -1}", "capture_offset", "[0, 1e+07] s"),
    _robot("one pixel",
           "{cameras: {front: {width: 1, height: 1, focal: !FocalLength {x: 100, y: 100}}}}",
           "cameras.front",
           "Invalid camera configuration: Center X (0) should lie in the range (0, 1)."),
    _camera("mount frame", "{X_PB: {base_frame: tail}}", "X_PB.base_frame", "'tail' is not a link"),
    # the IR sensors
    _ir("samples 1", "{samples: 1}", "samples", "[2, 64] (rays per fan)"),
    _ir("samples 1e6", "{samples: 1000000}", "samples", "got 1000000"),
    _ir("scan 1e9", "{scan_rate_hz: 1e9}", "scan_rate_hz", "(0, 1000] Hz"),
    _ir("scan 0", "{scan_rate_hz: 0}", "scan_rate_hz", "got 0"),
    _ir("range negative", "{maximum_range: -1}", "maximum_range", "(0, 100] m"),
    _ir("range inf", "{maximum_range: .inf}", "maximum_range", "got inf"),
    _ir("cone 200", "{dispersion_cone_angle: 200}", "dispersion_cone_angle", "[0, 180) deg"),
    _ir("model", "{model: laser}", "model", "not one of ideal, sharp_gp2d12"),
    _ir("noise", "{noise_std: -1}", "noise_std", "[0, 10] V"),
    _ir("threshold inf", "{change_threshold: .inf}", "change_threshold", "got inf"),
    _ir("mount inf", "{X_PB: {translation: [.inf, 0, 0]}}", "X_PB.translation[0]", "got inf"),
    _robot("sensor name", "{ir_sensors: {a.b: {}}}", "ir_sensors.a.b",
           "a sensor name must be letters, digits"),
    # the planar lidar
    _lidar("lidar 0 rays", "{samples: 0}", "samples", "[1, 10000] (rays per scan)"),
    _lidar("lidar 1e7 rays", "{samples: 10000000}", "samples", "got 10000000"),
    _lidar("lidar range negative", "{range_min: -1}", "range_min", "[0, 1000] m"),
    _lidar("lidar range inverted", "{range_min: 5, range_max: 2}", "range_min",
           "must be below range_max (2 m); got 5"),
    _lidar("lidar angles inverted", "{angle_min: 1, angle_max: -1}", "angle_max",
           "must be at least angle_min"),
    _lidar("lidar noise NaN", "{noise_std: .nan}", "noise_std", "NaN is not allowed"),
    _lidar("lidar noise negative", "{noise_std: -0.1}", "noise_std", "[0, 10] m"),
    _lidar("lidar rate 0", "{scan_rate_hz: 0}", "scan_rate_hz", "(0, 1000] Hz"),
    _lidar("lidar rate 1e6", "{scan_rate_hz: 1e6}", "scan_rate_hz", "got 1e+06"),
    _lidar("lidar dropout 2", "{dropout: 2}", "dropout", "[0, 1]"),
    _lidar("lidar on no link", "{X_PB: {base_frame: mast}}", "X_PB.base_frame",
           "'mast' is not a link"),
    # the bumper
    _bumper("bumper rate 0", "{rate_hz: 0}", "rate_hz", "(0, 1000] Hz"),
    _bumper("bumper rate 1e6", "{rate_hz: 1e6}", "rate_hz", "got 1e+06"),
    _bumper("bumper threshold NaN", "{force_threshold: .nan}", "force_threshold",
            "NaN is not allowed"),
    _bumper("bumper threshold negative", "{force_threshold: -1}", "force_threshold",
            "[0, 10000] N"),
    _bumper("bumper box negative", "{size: [0.02, -1, 0.04]}", "size[1]", "[0.001, 2] m"),
    _bumper("bumper box inf", "{size: [0.02, .inf, 0.04]}", "size[1]", "got inf"),
    _bumper("bumper box of two", "{size: [0.02, 0.2]}", "size", "needs 3 numbers"),
    _bumper("bumper on no link", "{X_PB: {base_frame: bonnet}}", "X_PB.base_frame",
            "'bonnet' is not a link"),
    _bumper("bumper geometry unknown", "{geometry: wheel}", "geometry",
            "'wheel' is not one of box, link"),
    _bumper("bumper link on the world", "{geometry: link, X_PB: {base_frame: world}}",
            "geometry", "a link of the robot; got world"),
    # the IMU
    _imu("imu rate 0", "{rate_hz: 0}", "rate_hz", "(0, 1000] Hz"),
    _imu("imu rate 1e6", "{rate_hz: 1e6}", "rate_hz", "got 1e+06"),
    _imu("imu gyro noise NaN", "{gyro_noise_density: .nan}", "gyro_noise_density",
         "NaN is not allowed"),
    _imu("imu gyro noise negative", "{gyro_noise_density: -1e-4}", "gyro_noise_density",
         "[0, 1] rad/s/sqrt(Hz)"),
    _imu("imu gyro walk inf", "{gyro_random_walk: .inf}", "gyro_random_walk", "got inf"),
    _imu("imu accel noise negative", "{accel_noise_density: -1}", "accel_noise_density",
         "[0, 10] m/s^2/sqrt(Hz)"),
    _imu("imu accel walk NaN", "{accel_random_walk: .nan}", "accel_random_walk",
         "NaN is not allowed"),
    _imu("imu on no link", "{X_PB: {base_frame: mast}}", "X_PB.base_frame",
         "'mast' is not a link"),
    _override("a list as a key", "world: {bodies: {b: {shape: !Box {[0.1, 4.2, 0.5]}}}}",
              "world.bodies.b.shape", "a key must be a name, got a list"),
    _override("a mapping as a name", "robots: {? {a: 1} : {}}", "robots",
              "a key must be a name, got a mapping"),
    _override("robot name with ?", "robots: {'a?b': {pose: {translation: [2, 0, 0]}}}",
              "robots.a?b", "a URL path segment"),
    # directives Drake's parser would crash on, or take a NaN pose from
    _override("empty add_frame", "directives: [{add_frame: {}}]", "directives[0].add_frame.name",
              "must not be empty"),
    _override("empty add_model", "directives: [{add_model: {}}]", "directives[0].add_model.file",
              "needs the model's URI"),
    _override("frame at inf", "directives: [{add_frame: {name: f, X_PF: {base_frame: world, "
              "translation: [0, 0, .inf]}}}]", "directives[0].add_frame.X_PF", "finite pose"),
    _override("two kinds", "directives: [{add_frame: {name: f, X_PF: {base_frame: world}}, "
              "add_model_instance: {name: m}}]", "directives[0]", "exactly one of"),
]

HAND_WRITTEN = FILES + READS + OVERRIDES + ROBOT_FILES
"""Every hand-written bad input."""


# --- generated: hostile values in every numeric field, edits of the shipped files -----------

HOSTILE_NUMBERS = (math.nan, math.inf, -math.inf, 0.0, -1.0, 1e-300, -1e-300, 1e300, -1e300,
                   1e9, 1e-7, 2.0**63, -(2.0**31) - 1)


def numeric_fields(scenario_file: Path = DEFAULT_SCENARIO) -> list[tuple[str, float, list]]:
    """Every number of the loaded scenario: (YAML path, value, the list it is an element of
    or None), lists element by element (`world.sun.direction[2]`), poses' translations too."""
    found: list[tuple[str, float, list]] = []

    def walk(value, path, within=None):
        if isinstance(value, bool) or value is None:
            return
        if isinstance(value, int | float):
            found.append((path, value, within))
        elif isinstance(value, list):
            for i, item in enumerate(value):
                walk(item, f"{path}[{i}]", value)
        elif isinstance(value, dict):
            for key, item in value.items():
                walk(item, f"{path}.{key}" if path else key)
        elif dc.is_dataclass(value):
            for f in dc.fields(value):
                if f.name != "commands":  # tagged: not plain YAML
                    walk(getattr(value, f.name), f"{path}.{f.name}" if path else f.name)
        elif type(value).__name__ == "Transform" and path.endswith(".pose"):
            translation = [float(v) for v in value.translation]
            for i, v in enumerate(translation):
                walk(v, f"{path}.translation[{i}]", translation)
        elif type(value).__name__ in ("MultibodyPlantConfig", "SimulatorConfig"):
            for f in type(value).__fields__:
                walk(getattr(value, f.name), f"{path}.{f.name}")

    walk(load_scenario(scenario_file), "")
    return found


def yaml_value(value) -> str:
    """`value` as YAML flow text (floats with YAML's .inf and .nan)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        if math.isnan(value):
            return ".nan"
        if math.isinf(value):
            return ".inf" if value > 0 else "-.inf"
        return repr(value)
    if isinstance(value, int):
        return str(value)
    if isinstance(value, list):
        return "[" + ", ".join(yaml_value(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{yaml_value(k)}: {yaml_value(v)}" for k, v in value.items()) + "}"
    if value is None:
        return "null"
    # JSON's string is YAML's double-quoted one, its control characters escaped: a raw line
    # break would split a one-line --override into two.
    return json.dumps(str(value))


def override_at(path: str, value, original: list | None = None) -> str:
    """An --override setting `path` (`a.b[2]`: element 2 of the list `original`) to `value`."""
    m = re.fullmatch(r"(.*)\[(\d+)\]", path)
    if m:
        items = [yaml_value(v) for v in original]
        items[int(m.group(2))] = yaml_value(value)
        path, text = m.group(1), "[" + ", ".join(items) + "]"
    else:
        text = yaml_value(value)
    for key in reversed(path.split(".")):
        text = f"{{{key}: {text}}}"
    return text


def shipped_scenarios() -> list[Path]:
    return sorted(SCENARIOS_DIR.glob("*.yaml"))


EDIT_TOKENS = ("[", "]", "{", "}", ":", ": ", "-", "- ", "!", "!Box", "&a ", "*a", "\t", "\n",
               "  ", "'", '"', "#", ".inf", "-.inf", ".nan", "1e999", "-1", "0", "1e-300",
               "\x00", "\ufeff", "\u00e9", "\x85", "\\", "%", "@", "`", "|", ">", "?", ",")
"""Text an edit inserts: YAML's punctuation, hostile numbers, odd characters."""


class RandomDraw:
    """The choices a mutation makes, drawn from a seeded generator (tools/hostile_inputs.py;
    the test draws the same mutations with hypothesis instead: its `HypothesisDraw`)."""

    def __init__(self, seed: int):
        self.random = random.Random(seed)

    def choice(self, options):
        return self.random.choice(list(options))

    def integer(self, low: int, high: int) -> int:
        return self.random.randint(low, high)

    def value(self):
        """A hostile value: a number of HOSTILE_NUMBERS or any float, text, a list, a
        mapping, nothing."""
        r = self.random
        kind = r.randrange(6)
        if kind == 0:
            return r.choice(HOSTILE_NUMBERS)
        if kind == 1:
            return r.choice((r.uniform(-1e6, 1e6), 10.0 ** r.uniform(-320, 308)))
        if kind == 2:
            return "".join(chr(r.randrange(32, 0x2FFF)) for _ in range(r.randrange(6)))
        if kind == 3:
            return [r.choice(HOSTILE_NUMBERS) for _ in range(r.randrange(5))]
        if kind == 4:
            return {"x": r.choice(HOSTILE_NUMBERS)}
        return None


def mutated_override(draw) -> tuple[Path, str, str]:
    """(scenario file, field path, --override text): a hostile value (`draw.value()`) in a
    numeric field of a shipped scenario. `draw` makes the choices (RandomDraw, or the test's
    hypothesis draw)."""
    file = draw.choice(shipped_scenarios())
    path, _, within = draw.choice(_numeric_fields(file))
    return file, path, override_at(path, draw.value(), within)


def mutated_file(draw) -> tuple[str, str]:
    """(file name, text): a shipped scenario's text with 1-4 edits (an insertion from
    EDIT_TOKENS, a deletion, a duplicated line, a number swapped for a hostile one)."""
    file = draw.choice(shipped_scenarios())
    text = file.read_text()
    for _ in range(draw.integer(1, 4)):
        at = draw.integer(0, len(text))
        edit = draw.choice(("insert", "delete", "duplicate line", "number"))
        if edit == "insert":
            text = text[:at] + draw.choice(EDIT_TOKENS) + text[at:]
        elif edit == "delete":
            text = text[:at] + text[at + draw.integer(1, 20):]
        elif edit == "duplicate line":
            start = text.rfind("\n", 0, at) + 1
            end = text.find("\n", at) + 1 or len(text)
            text = text[:end] + text[start:end] + text[end:]
        else:
            numbers = list(re.finditer(r"-?\d+(\.\d+)?(e-?\d+)?", text))
            if numbers:
                m = draw.choice(numbers)
                text = text[:m.start()] + yaml_value(draw.choice(HOSTILE_NUMBERS)) + text[m.end():]
    return file.name, text


@functools.cache
def _numeric_fields(file: Path):
    return numeric_fields(file)


def related(error: re.Match, path: str) -> bool:
    """Whether an error (an ERROR_LINE match) is about a change at `path`: it names the same
    field, one that holds it (a list, a pose) or one inside it; or the text is not YAML (a
    generated string may hold a character YAML refuses)."""
    field = error["field"]
    return (field == path or path.startswith((f"{field}.", f"{field}["))
            or field.startswith(path) or error["message"].startswith("not valid YAML"))


# --- the corpus run as a whole (tools/hostile_inputs.py) ------------------------------------


@dc.dataclass
class Tally:
    """How one kind of input fared."""

    kind: str
    inputs: int = 0
    refused: int = 0
    """Refused with the one clear line, in time."""
    accepted: int = 0
    """Accepted: a generated input that happened to be valid."""
    defects: list[str] = dc.field(default_factory=list)
    slowest: float = 0.0
    """CPU seconds of the slowest input."""

    def add(self, outcome: Outcome, found: list[str], label: str) -> None:
        self.inputs += 1
        self.slowest = max(self.slowest, outcome.cpu_seconds)
        if outcome.error is None and outcome.other is None and not outcome.hung:
            self.accepted += 1
        elif found:
            self.defects.append(f"{label}: {'; '.join(found)} ({outcome.error or outcome.other})")
        else:
            self.refused += 1


def prepare(case: Case, directory: Path) -> tuple[str, Path | None]:
    """(the source its error must name, the file to load: None for the default scenario)
    of a case, its file written (or its FIFO made) under `directory`."""
    if case.text is not None:
        return "--override", None
    for name, content in case.files:
        if isinstance(content, int):
            with open(directory / name, "wb") as f:
                f.truncate(content)
        else:
            (directory / name).write_bytes(content)
    if case.data is not None:
        path = directory / "bad.yaml"
        path.write_bytes(case.data)
        return (str((directory / case.blame).resolve()) if case.blame else str(path)), path
    fifo = directory / "fifo"
    if "{fifo}" in case.path and not fifo.exists():
        os.mkfifo(fifo)
    path = case.path.format(tmp=directory, fifo=fifo)
    return path, Path(path)


def run_hand_written(directory: Path, progress=None) -> Tally:
    """Every HAND_WRITTEN case, files written under `directory`."""
    tally = Tally("hand-written (bytes, special files, every bound, the poses)")
    for case in HAND_WRITTEN:
        source, path = prepare(case, directory)
        outcome = load(path, (case.text,) if case.text is not None else ())
        found = problems(outcome, source, case.field, case.words, case.line)
        if outcome.error is None and outcome.other is None and not outcome.hung:
            found = ["accepted"]  # every hand-written input is invalid
            outcome.other = "accepted"
        tally.add(outcome, found, case.name)
        if progress:
            progress()
    return tally


def run_generated(directory: Path, examples: int, seed: int = 1, progress=None) -> list[Tally]:
    """`examples` inputs of each generated kind, drawn by RandomDraw(seed)."""
    overrides = Tally("a hostile value in a numeric field of a shipped scenario (generated)")
    edits = Tally("1-4 edits of a shipped scenario file's text (generated)")
    draw = RandomDraw(seed)
    for _ in range(examples):
        file, path, text = mutated_override(draw)
        outcome = load(file, (text,))
        found = problems(outcome, "--override", line=1)
        if not found and outcome.error and not related(outcome.match(), path):
            found = [f"names {outcome.match()['field']!r} for a change at {path}"]
        overrides.add(outcome, found, text)
        if progress:
            progress()
    for _ in range(examples):
        name, text = mutated_file(draw)
        path = directory / name
        path.write_bytes(text.encode("utf-8", "surrogatepass"))
        outcome = load(path)
        found = problems(outcome, str(path))
        if not found and outcome.error and outcome.match()["line"] is None:
            found = ["no line"]
        edits.add(outcome, found, repr(text[:80]))
        if progress:
            progress()
    return [overrides, edits]


def table(tallies: list[Tally]) -> str:
    lines = ["| inputs | count | refused with the one line | accepted (valid) | defects | "
             "slowest (CPU s) |", "|---|---|---|---|---|---|"]
    for t in tallies:
        lines.append(f"| {t.kind} | {t.inputs} | {t.refused} | {t.accepted} | "
                     f"{len(t.defects)} | {t.slowest:.2f} |")
    total = sum(t.inputs for t in tallies)
    lines.append(f"| all | {total} | {sum(t.refused for t in tallies)} | "
                 f"{sum(t.accepted for t in tallies)} | {sum(len(t.defects) for t in tallies)} "
                 f"| {max(t.slowest for t in tallies):.2f} |")
    return "\n".join(lines)


# --- study files and the tools' inputs (`--from DIR`, logs, arguments) ----------------------


@dc.dataclass(frozen=True)
class StudyCase:
    """A bad study file (its `text` after `scenario: ../corobot.yaml`): the field its error
    must name and words of its message."""

    name: str
    text: str
    field: str
    words: str


_GRID_1E7 = "grid:\n" + "".join(f"  robots.corobot.p{i}: [{', '.join('0' * 10)}]\n"
                                for i in range(7))

STUDIES = [
    StudyCase("duration -1", "duration: -1\n", "duration", "(0, 100000] s"),
    StudyCase("duration inf", "duration: .inf\n", "duration", "got inf"),
    StudyCase("settle negative", "settle: -1\n", "settle", "[0, 1000] s"),
    StudyCase("seeds 1e9", "seeds: 1000000000\n", "seeds", "[1, 100000]"),
    StudyCase("seeds 0", "seeds: 0\n", "seeds", "got 0"),
    StudyCase("seeds float", "seeds: 1e9\n", "seeds", "expected an integer"),
    StudyCase("seeds empty", "seeds: []\n", "seeds", "at least one seed"),
    StudyCase("seed beyond Drake's int", "seeds: [99999999999]\n", "seeds[0]", "Drake's int"),
    StudyCase("grid of 10^7 points", _GRID_1E7, "grid.robots.corobot.p5", "more than 100000 runs"),
    StudyCase("uniform min > max", "random:\n  robots.corobot.contact.friction: "
              "!Uniform {min: 2, max: 1}\n", "random.robots.corobot.contact.friction.max",
              "must be >= min (2); got 1"),
    StudyCase("uniform inf", "random:\n  a.b: !Uniform {max: .inf}\n", "random.a.b.max",
              "finite"),
    StudyCase("normal sd negative", "random:\n  a.b: !Normal {sd: -1}\n", "random.a.b.sd",
              "a standard deviation"),
    StudyCase("choice empty", "random:\n  a.b: !Choice {values: []}\n", "random.a.b.values",
              "at least one value"),
    # (a program's field: a scenario path's type is its scenario's, which this corpus lacks)
    StudyCase("grid of mixed values", "drive_test: {}\ngrid:\n  drive_test.loops: "
              "[3, fast, null, true]\n", "grid.drive_test.loops[1]",
              "loops: expected an integer, got 'fast'"),
    StudyCase("steady metric on a short run", "duration: 0.3\nmetrics: [steady_speed]\n",
              "metrics[0]", "needs runs of at least 1 s"),
]


def load_study_text(directory: Path, case: StudyCase) -> tuple[str, Outcome]:
    """(the file's name, what loading it gave)."""
    from corobot_drake.study.spec import load_study

    path = directory / "study.yaml"
    path.write_text("scenario: ../corobot.yaml\n" + case.text)
    outcome = Outcome()
    start = time.thread_time()
    try:
        load_study(path)
    except ScenarioError as e:
        outcome.error = str(e)
    except Exception as e:  # a defect
        outcome.other = f"{type(e).__name__}: {str(e)[:200]}"
    outcome.cpu_seconds = time.thread_time() - start
    return str(path), outcome


@dc.dataclass(frozen=True)
class ToolCase:
    """A tool run on a bad input: `argv` (`{tmp}`: a scratch directory holding `files`,
    path -> bytes); its stderr must be one line starting `error: ` and holding `words`."""

    name: str
    tool: str
    argv: tuple[str, ...]
    words: str
    files: tuple[tuple[str, bytes], ...] = ()


_RUNS_HEADER = b"a,b\n1,2\n"
_LOG_HEADER = b"time,left_power,right_power,left_ticks,right_ticks,x,y,yaw\n"

TOOLS = [
    ToolCase("landing: no runs", "landing_errors", ("--from", "{tmp}"),
             "{tmp}/drive/runs.csv: (top level): no such file: run the study first"),
    ToolCase("landing: no directory", "landing_errors", ("--from", "{tmp}/nowhere"),
             "no such directory"),
    ToolCase("landing: another study's runs", "landing_errors", ("--from", "{tmp}"),
             "{tmp}/drive/runs.csv:1: columns: lacks run, seed", (("drive/runs.csv",
                                                                  _RUNS_HEADER),)),
    ToolCase("landing: runs not UTF-8", "landing_errors", ("--from", "{tmp}"),
             "{tmp}/drive/runs.csv:1: (top level): not UTF-8", (("drive/runs.csv",
                                                                 b"\xff\xfe"),)),
    ToolCase("landing: runs.csv empty", "landing_errors", ("--from", "{tmp}"),
             "empty: no header", (("drive/runs.csv", b""),)),
    ToolCase("landing: --workers 0", "landing_errors", ("--workers", "0"),
             "argument --workers: must be in [1, 1024]"),
    ToolCase("landing: --plot under a file", "landing_errors",
             ("--from", "{tmp}", "--plot", "{tmp}/f/x.png"), "is not a directory",
             (("f", b"x"),)),
    ToolCase("tire grip: no runs", "tune_tire_grip", ("--from", "{tmp}"),
             "{tmp}/box/runs.csv: (top level): no such file"),
    ToolCase("tire grip: --out a file", "tune_tire_grip", ("--out", "{tmp}/f"),
             "is a file, not a directory", (("f", b"x"),)),
    ToolCase("odometry: log lacks columns", "calibrate_odometry", ("{tmp}/log.csv",),
             "header lacks column(s)", (("log.csv", b"time,left_ticks\n1,2\n"),)),
    ToolCase("odometry: log empty", "calibrate_odometry", ("{tmp}/log.csv",),
             "empty file", (("log.csv", b""),)),
    ToolCase("odometry: log not numbers", "calibrate_odometry", ("{tmp}/log.csv",),
             "{tmp}/log.csv:2: left_ticks is not a number",
             (("log.csv", _LOG_HEADER + b"0,a,b,c,d,e,f,g\n"),)),
    ToolCase("odometry: log not UTF-8", "calibrate_odometry", ("{tmp}/log.csv",),
             "not UTF-8", (("log.csv", b"\xff\xfe"),)),
    ToolCase("odometry: log a device", "calibrate_odometry", ("/dev/zero",),
             "cannot read a device"),
    ToolCase("odometry: ticks 0", "calibrate_odometry",
             ("{tmp}/log.csv", "--ticks-per-revolution", "0"), "must be in [1, 1000000]"),
    ToolCase("fit: log a directory", "fit_drive_log", ("{tmp}",), "cannot read a directory"),
    ToolCase("fit: --write missing", "fit_drive_log", ("x.csv", "--write", "{tmp}/no.yaml"),
             "no such file"),
    ToolCase("fit: --simulate -1", "fit_drive_log", ("--simulate", "-1", "5"),
             "--simulate: motor_torque_scaling must be in (0, 200] rad/s; got -1"),
    ToolCase("drive test: --loops -1", "drive_test", ("--loops", "-1"), "[1, 100]"),
    ToolCase("drive test: --seeds 0", "drive_test", ("--seeds", "0"), "[1, 10000]"),
    ToolCase("drive test: --power 7", "drive_test", ("--power", "7"), "(0, 1]"),
    ToolCase("torque: --scaling -1", "tune_motor_torque_scaling", ("--scaling", "-1"),
             "(0, 200] rad/s"),
    ToolCase("torque: scenario a directory", "tune_motor_torque_scaling",
             ("--scenario", "{tmp}"), "cannot read a directory"),
    ToolCase("snapshot: --width 0", "snapshot", ("--width", "0"), "[1, 4096] pixels"),
    ToolCase("snapshot: --pose far away", "snapshot",
             ("--pose", "1e9,0,0", "--output", "{tmp}/s.png"),
             "<Python scenario>: robots.corobot.pose.translation[0]: must be in [-10000"),
    ToolCase("bench: --seconds 0", "bench", ("--seconds", "0"),
             "argument --seconds: must be in (0, 3600] s; got 0"),
    ToolCase("bench: --seconds nan", "bench", ("--seconds", "nan"), "(0, 3600] s; got nan"),
    ToolCase("bench: --repeats -1", "bench", ("--repeats", "-1"), "[1, 1000]"),
    ToolCase("bench: --robots 1,0", "bench", ("--robots", "1,0"), "--robots: must be in [1, 256]"),
    ToolCase("bench: --plants nothing", "bench", ("--plants", "rigid"), "is in none of"),
    ToolCase("bench camera: --frames 0", "bench_camera", ("--frames", "0"), "[1, 100000]"),
    ToolCase("bench gym: --episodes 0", "bench_gym", ("--episodes", "0"), "[1, 10000]"),
    ToolCase("bench IR: --seconds inf", "bench_ir", ("--seconds", "inf"), "(0, 3600] s; got inf"),
    ToolCase("bench memory: warm-up past the end", "bench_memory",
             ("--sim-minutes", "1", "--warmup-minutes", "2"), "less than --sim-minutes (1)"),
    ToolCase("bench recording: --repeats 0", "bench_recording", ("--repeats", "0"), "[1, 1000]"),
    ToolCase("bench study: --duration -1", "bench_study", ("--duration", "-1"), "(0, 3600] s"),
    ToolCase("train: --generations 0", "train_policy", ("--generations", "0"), "[1, 1000]"),
    ToolCase("train: --sigma nan", "train_policy", ("--sigma", "nan"), "(0, 100]; got nan"),
    ToolCase("train: --elite above --population", "train_policy", ("--elite", "11"),
             "at most --population (8)"),
    ToolCase("train: --address where no Ray cluster answers", "train_policy",
             ("--address", "127.0.0.1:1"), "--address 127.0.0.1:1: no Ray cluster answers"),
    ToolCase("train: --address that is no address", "train_policy",
             ("--address", "not an address"), "not a Ray cluster's address"),
    ToolCase("train: --evaluate without a policy", "train_policy",
             ("--evaluate", "--policy", "{tmp}/none.json"), "no such file"),
    ToolCase("train: --evaluate a file that is no policy", "train_policy",
             ("--evaluate", "--policy", "{tmp}/policy.json"), "not a saved policy",
             (("policy.json", b'{"features": ["x"], "weights": {}}'),)),
]


def run_tool(case: ToolCase, directory: Path) -> tuple[int, str, str]:
    """(exit status, stderr, the words with `{tmp}` filled) of the tool run in-process."""
    import contextlib
    import importlib.util
    import io
    import sys

    for name, data in case.files:
        path = directory / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(data)
    tool = Path(__file__).resolve().parents[1] / "tools" / f"{case.tool}.py"
    spec = importlib.util.spec_from_file_location(f"tool_{case.tool}", tool)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up
    spec.loader.exec_module(module)
    err = io.StringIO()
    argv = [a.format(tmp=directory) for a in case.argv]
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        try:
            status = module.main(argv)
        except SystemExit as e:  # argparse's errors
            status = e.code
    return status, err.getvalue(), case.words.format(tmp=directory)


def run_studies_and_tools(directory: Path, progress=None) -> list[Tally]:
    """Every STUDIES and TOOLS case (each tool's in a directory of its own under
    `directory`)."""
    studies = Tally("bad study files (bounds, runs, distributions)")
    for case in STUDIES:
        source, outcome = load_study_text(directory, case)
        studies.add(outcome, problems(outcome, source, case.field, case.words) or (
            ["accepted"] if outcome.error is None and outcome.other is None else []), case.name)
        if progress:
            progress()
    tools = Tally("the tools' bad inputs (--from DIR, logs, arguments, outputs)")
    for i, case in enumerate(TOOLS):
        scratch = directory / f"tool{i}"
        scratch.mkdir()
        start = time.process_time()
        status, err, words = run_tool(case, scratch)
        lines = err.strip().splitlines()
        outcome = Outcome(error=lines[0] if lines else None,
                          cpu_seconds=time.process_time() - start)
        found = [] if status == 2 and len(lines) == 1 and lines[0].startswith(
            "error: ") and words in lines[0] else [f"exit {status}: {err.strip()[:200]!r}"]
        tools.add(outcome, found, case.name)
        if progress:
            progress()
    return [studies, tools]


# --- the ROS 2 node's Simulation Interfaces: bad requests (tests/service/test_ros2_simulation.py)


@dc.dataclass(frozen=True)
class RosRequest:
    """A bad request to the node's Simulation Interfaces: the `service` (its name) and `srv`
    (its simulation_interfaces type), the request's `fields` (nested dicts for messages; in a
    string, `{dir}` is the directory the `files` (name, text) are written to), the `code` it
    must get (a name of the service's Response, or of simulation_interfaces/Result) and
    `words` its one-line message must hold. The node keeps serving after each."""

    name: str
    service: str
    srv: str
    fields: dict
    code: str
    words: str
    files: tuple = ()


_AT = {"pose": {"position": {"x": 1.0, "z": 0.1}, "orientation": {"w": 1.0}}}
"""A spawn's initial_pose: free ground beside the default scenario's Corobot."""
_BOX = {"resource_string": "shape: !Box {size: [0.2, 0.2, 0.2]}"}
_MESH_MISSING = """<?xml version="1.0"?>
<sdf version="1.7">
  <model name="thing">
    <link name="base">
      <inertial><mass>1.0</mass></inertial>
      <visual name="look"><geometry><mesh><uri>missing_part.obj</uri></mesh></geometry></visual>
    </link>
  </model>
</sdf>
"""


def _spawn(case: str, resource: dict, code: str, words: str, files: tuple = (),
           **fields) -> RosRequest:
    """A SpawnEntity request named `case` (`fields`: the request's, over a body "b" at
    `_AT`)."""
    return RosRequest(case, "spawn_entity", "SpawnEntity", {
        "name": "b", "initial_pose": _AT, "entity_resource": resource, **fields}, code, words,
        files)


def _broken_burger() -> tuple[str, int]:
    """The Burger's robot file with a negative wheel radius, and that line's number."""
    from corobot_drake.robots import ROBOTS

    text = ROBOTS["burger"].read_text().replace("radius: 0.033 ", "radius: -1 ")
    return text, 1 + next(i for i, line in enumerate(text.splitlines()) if "radius: -1" in line)


def ros_requests() -> list[RosRequest]:
    """The corpus of bad Simulation Interfaces requests (the default scenario's node)."""
    burger, line = _broken_burger()
    return [
        *(RosRequest(f"steps {n}", "step_simulation", "StepSimulation", {"steps": n},
                     "RESULT_OPERATION_FAILED", "steps: must be in [1, 1000000]")
          for n in (0, 10**12)),
        RosRequest("state of nobody", "get_entity_state", "GetEntityState",
                   {"entity": "nobody"}, "RESULT_NOT_FOUND", "no entity named 'nobody'"),
        RosRequest("NaN pose", "set_entity_state", "SetEntityState", {
            "entity": "corobot", "set_pose": True,
            "state": {"pose": {"position": {"x": math.nan}}}},
            "INVALID_POSE", "state.pose.position.x: must be a finite"),
        RosRequest("half a quaternion", "set_entity_state", "SetEntityState", {
            "entity": "corobot", "set_pose": True,
            "state": {"pose": {"orientation": {"w": 0.5}}}},
            "INVALID_POSE", "state.pose.orientation: must be a unit quaternion"),
        _spawn("a name taken", _BOX, "NAME_NOT_UNIQUE", "is taken", name="giant_box"),
        _spawn("not a name", _BOX, "NAME_INVALID", "is not a name", name="9 lives"),
        _spawn("no resource", {}, "NO_RESOURCE", "both uri"),
        _spawn("a USD file", {"uri": "/x/robot.usd"}, "UNSUPPORTED_FORMAT",
               "spawn formats are yaml"),
        _spawn("an unknown shape", {"resource_string": "shape: !Cone {}"},
               "RESOURCE_PARSE_ERROR", "entity_resource.resource_string: "),
        _spawn("no such model file", {"uri": "/nowhere/x.sdf"}, "RESOURCE_PARSE_ERROR",
               "entity_resource.uri: '/nowhere/x.sdf': "),
        _spawn("a model's mesh missing", {"uri": "{dir}/thing.sdf"}, "MISSING_ASSETS",
               "resolved to '{dir}/missing_part.obj' which does not exist",
               (("thing.sdf", _MESH_MISSING),)),
        _spawn("SDFormat as a string", {"resource_string": _MESH_MISSING},
               "UNSUPPORTED_FORMAT", "entity_resource.resource_string: XML (a model's"),
        _spawn("a body file's bad mass", {"uri": "file://{dir}/body.yaml"},
               "RESOURCE_PARSE_ERROR", "entity_resource.uri: {dir}/body.yaml:3: mass: must be in ",
               (("body.yaml", "# a box too light\nshape: !Box {size: [0.2, 0.2, 0.2]}\n"
                              "mass: -1\n"),)),
        _spawn("a body string's unknown field",
               {"resource_string": "shape: !Box {size: [0.2, 0.2, 0.2]}\n\ncolour: red"},
               "RESOURCE_PARSE_ERROR", "entity_resource.resource_string: line 3: colour: "
                                       "unknown "),
        _spawn("a body string's broken YAML",
               {"resource_string": "shape: !Box {size: [0.2, 0.2, 0.2]}\nmass: [1"},
               "RESOURCE_PARSE_ERROR", "entity_resource.resource_string: line 2: (top level): "
                                       "not valid YAML"),
        _spawn("a body's mesh missing",
               {"resource_string": "shape: !Mesh {filename: /nowhere/part.obj}\nfixed: true"},
               "MISSING_ASSETS", "entity_resource.resource_string: line 1: shape.filename: "
                                 "/nowhere/part.obj: cannot read the file"),
        _spawn("no such robot", {"uri": "turtlebot"}, "RESOURCE_PARSE_ERROR",
               "entity_resource.uri: 'turtlebot' is neither a shipped robot (corobot, burger, "
               "pioneer) nor a robot file"),
        _spawn("a robot file's bad wheel", {"uri": "file://{dir}/broken.yaml"},
               "RESOURCE_PARSE_ERROR",
               f"entity_resource.uri: {{dir}}/broken.yaml:{line}: wheels.radius: must be in "
               "(0, 100] m", (("broken.yaml", burger),)),
        _spawn("a robot's name taken", {"uri": "burger"}, "NAME_NOT_UNIQUE", "is taken",
               name="corobot"),
        _spawn("a body's name for a robot", {"uri": "burger"}, "NAME_NOT_UNIQUE", "is taken",
               name="giant_box"),
        _spawn("a robot elsewhere", {"uri": "burger"}, "RESULT_FEATURE_UNSUPPORTED",
               "entity_namespace: a robot's topics and frames are under its name (/b/...)",
               entity_namespace="/elsewhere"),
        _spawn("a robot file as a string",
               {"resource_string": "model: burger.sdf\nwheels: {left: [l], right: [r]}"},
               "RESULT_FEATURE_UNSUPPORTED",
               "entity_resource.resource_string: a robot file: give its uri instead"),
        RosRequest("delete nobody", "delete_entity", "DeleteEntity", {"entity": "nobody"},
                   "RESULT_NOT_FOUND", "no entity named"),
        RosRequest("delete the only robot", "delete_entity", "DeleteEntity",
                   {"entity": "corobot"}, "RESULT_OPERATION_FAILED",
                   "entity: 'corobot' is the only robot"),
    ]
