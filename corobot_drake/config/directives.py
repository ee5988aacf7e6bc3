"""The scenario's model directives, checked as the world's bodies are, before the station.

`check_directives` walks the directives and the directives files they include (a file that
includes itself, directly or not, is refused: Drake recursed until it crashed), reads each
model file and the mesh files it names as `config/mesh_files.py` reads a world body's (regular
files within a budget, before Drake reads them), then has Drake process the directives into a
scratch plant with a SceneGraph and checks what they add: each body's mass and inertia, and a
free body's contact (`validate.RIGID_ON_GROUND`). It returns each added collision shape and its
start pose for `placement` (a robot inside a model is refused, and a model inside a robot).
"""

import dataclasses as dc
import logging
import re
from pathlib import Path

import numpy as np
from pydrake.common.yaml import yaml_load_typed
from pydrake.geometry import Convex, HalfSpace, Mesh, SceneGraph, Sphere
from pydrake.multibody.parsing import ModelDirectives, ProcessModelDirectives
from pydrake.multibody.plant import MultibodyPlant

from corobot_drake.config import schema as sc
from corobot_drake.config.mesh_files import MESH_EXTENSIONS, MeshFileError, check_mesh_file
from corobot_drake.limits import MESH_SCALE
from corobot_drake.resources import make_parser, package_map

MAX_MODEL_BYTES = 4 << 20
"""A model file's (URDF, SDFormat, MJCF) largest size."""
MAX_INCLUDE_DEPTH = 8
"""Directives files included within each other at most this deep."""

_MESH_TAG = re.compile(r"<mesh\b([^>]*?)(/>|>(.*?)</mesh>)", re.S)
_ATTRIBUTE = r"""\b{}\s*=\s*["']([^"']*)["']"""
_ELEMENT = r"<{0}>\s*([^<]*?)\s*</{0}>"
_COLLISION = re.compile(r"<collision\b.*?</collision>", re.S)
"""A URDF or SDFormat collision element: its mesh is hulled for contact."""
HULLED_EXTENSIONS = (".obj", ".gltf", ".vtk")
"""The mesh files Drake builds a collision shape from (its convex hull): not GLB."""


class DirectiveError(ValueError):
    """A directive that cannot be used: `path` the field at fault, `str()` what is wrong."""

    def __init__(self, path: str, message: str):
        super().__init__(message)
        self.path = path


@dc.dataclass(frozen=True)
class ModelShape:
    """One collision shape of a model the directives add, where it starts."""

    name: str
    """`model::body`."""
    path: str
    """The directive's field (`directives[2].add_model`)."""
    shape: object
    X_WG: object
    anchored: bool
    """Welded to the world (else it moves)."""


def resolve(uri: str, base: Path) -> Path:
    """A file path for a `package://`, `file://` URI or a path (relative ones against `base`)."""
    if uri.startswith("package://"):
        return Path(package_map().ResolveUrl(uri))
    path = Path(uri.removeprefix("file://"))
    return path if path.is_absolute() else base / path


def check_directives(directives: list, world_bodies: dict, rigid_on_ground: str
                     ) -> list[ModelShape]:
    """Every directive's files, then what Drake makes of them (module docstring);
    DirectiveError at the first problem."""
    for i, directive in enumerate(directives):
        _check_files(directive, f"directives[{i}]", Path.cwd(), ())
    plant, scene_graph = MultibodyPlant(0.0), SceneGraph()
    plant.RegisterAsSourceForSceneGraph(scene_graph)
    for name, body in world_bodies.items():  # what a directive may weld to, where it is
        added = plant.AddRigidBody(name, plant.AddModelInstance(name))
        plant.WeldFrames(plant.world_frame(), added.body_frame(),
                         body.pose.GetDeterministicValue())
    warnings = _DrakeWarnings()
    try:  # all at once: a weld refers to the models added before it
        with warnings:
            added = ProcessModelDirectives(ModelDirectives(directives=directives), plant,
                                           make_parser(plant))
        plant.Finalize()
    except Exception as e:  # Drake's message (it names the file or frame), one line
        raise DirectiveError("directives", sc.one_line(e).removeprefix("error: ")) from None
    for message in warnings.messages:  # Drake replaces an inertia it cannot use, and warns
        if "inertia" in message:
            where = message.split(": warning:")[0]
            failed = re.search(r"condition '([^']*)' failed", message)
            raise DirectiveError("directives", f"{where}: a mass or inertia no body has"
                                 + (f" ({failed.group(1)} failed)" if failed else ""))
    paths = _directive_paths(directives)
    return _model_shapes(plant, scene_graph, added, paths, rigid_on_ground)


class _DrakeWarnings(logging.Handler):
    """Collects the messages Drake's parser logs while in a `with` block."""

    def __init__(self):
        super().__init__(logging.WARNING)
        self.messages: list[str] = []

    def emit(self, record: logging.LogRecord) -> None:
        self.messages.append(record.getMessage())

    def __enter__(self):
        log = logging.getLogger("drake")
        self._saved = log.level, log.propagate, log.filters
        log.setLevel(logging.WARNING)  # whatever quieted it: these are read here
        log.filters = []
        log.propagate = False  # and reported once, as the check's line (the station's parse
        log.addHandler(self)   # warns again)
        return self

    def __exit__(self, *exc) -> None:
        log = logging.getLogger("drake")
        log.removeHandler(self)
        log.level, log.propagate, log.filters = self._saved


REQUIRED = {
    "add_model": ("file", "name"),
    "add_model_instance": ("name",),
    "add_frame": ("name",),
    "add_weld": ("parent", "child"),
    "add_collision_filter_group": ("name",),
    "add_directives": ("file",),
}
"""What each kind of directive must name (Drake checks these with an assertion, or not at all:
an empty `add_frame` or `add_model` crashed the parser)."""


def directive_problem(directive) -> tuple[str, str] | None:
    """(field, what is wrong) when a directive is not exactly one kind with its names given."""
    kinds = [k for k in REQUIRED if getattr(directive, k) is not None]
    if len(kinds) != 1:
        return "", (f"needs exactly one of {', '.join(REQUIRED)}; got "
                    f"{', '.join(kinds) or 'none'}")
    (kind,) = kinds
    value = getattr(directive, kind)
    for name in REQUIRED[kind]:
        if not getattr(value, name):
            return f".{kind}.{name}", "must not be empty"
    if kind == "add_frame" and not value.X_PF.base_frame:
        return f".{kind}.X_PF.base_frame", "must name the frame the new frame is fixed to"
    for name in ("X_PF", "X_PC"):
        transform = getattr(value, name, None)
        if transform is not None and not _finite_pose(transform):
            return f".{kind}.{name}", "must be a finite pose (a translation in m, a rotation)"
    return None


def _finite_pose(transform) -> bool:
    try:
        return bool(np.isfinite(transform.GetDeterministicValue().GetAsMatrix4()).all())
    except Exception:  # a random pose, or a rotation Drake cannot make
        return False


def _check_files(directive, path: str, base: Path, chain: tuple[Path, ...]) -> None:
    problem = directive_problem(directive)
    if problem is not None:
        raise DirectiveError(path + problem[0], problem[1])
    for field, check in (("add_model", _check_model_file), ("add_directives", _check_included)):
        value = getattr(directive, field)
        if value is None:
            continue
        try:
            file = resolve(value.file, base)
        except RuntimeError as e:  # an unknown package, a file it does not have
            raise DirectiveError(f"{path}.{field}.file",
                                 sc.one_line(e).removeprefix("error: ")) from None
        check(file, f"{path}.{field}.file", *(() if field == "add_model" else (chain,)))


def _check_included(file: Path, path: str, chain: tuple[Path, ...]) -> None:
    """A directives file and, in turn, what it includes."""
    file = file.resolve()
    if file in chain:
        loop = " -> ".join(p.name for p in (*chain[chain.index(file):], file))
        raise DirectiveError(path, f"{file}: a directives file includes itself ({loop})")
    if len(chain) >= MAX_INCLUDE_DEPTH:
        raise DirectiveError(path, f"{file}: directives files included more than "
                             f"{MAX_INCLUDE_DEPTH} deep")
    try:
        text = sc.read_text(file, kind="a directives file is a YAML file")
        included = yaml_load_typed(schema=ModelDirectives, data=text)
    except sc.ScenarioError as e:
        raise DirectiveError(path, f"{file}: {e.message}") from None
    except Exception as e:
        raise DirectiveError(path, f"{file}: not Drake model directives "
                             f"({sc.one_line(e)[:120]})") from None
    for directive in included.directives:  # blamed on the top-level include
        _check_files(directive, path.removesuffix(".add_directives.file"), file.parent,
                     (*chain, file))


def _check_model_file(file: Path, path: str) -> None:
    """A model file within its budget, and every mesh file it names."""
    try:
        text = sc.read_text(file, kind="a model is a URDF, SDFormat or MJCF file",
                            max_bytes=MAX_MODEL_BYTES)
    except sc.ScenarioError as e:
        raise DirectiveError(path, f"{file}: {e.message}") from None
    base = _mjcf_mesh_dir(text, file.parent) if file.suffix.lower() == ".xml" else file.parent
    collisions = [m.span() for m in _COLLISION.finditer(text)]
    for match in _MESH_TAG.finditer(text):
        attributes, body = match.group(1), match.group(3) or ""
        found = (re.search(_ATTRIBUTE.format("filename"), attributes)
                 or re.search(_ATTRIBUTE.format("file"), attributes)
                 or re.search(_ELEMENT.format("uri"), body))
        if found is None:
            continue
        scale = (re.search(_ATTRIBUTE.format("scale"), attributes)
                 or re.search(_ELEMENT.format("scale"), body))
        mesh, what = resolve(found.group(1), base), f"{file}: mesh {found.group(1)!r}"
        _check_model_mesh(mesh, scale and scale.group(1), what, path)
        if (any(a <= match.start() < b for a, b in collisions)
                and mesh.suffix.lower() not in HULLED_EXTENSIONS):
            raise DirectiveError(path, f"{what}: a collision mesh is one of "
                                 f"{', '.join(HULLED_EXTENSIONS)} (Drake hulls no other)")


def _mjcf_mesh_dir(text: str, model_dir: Path) -> Path:
    """Where an MJCF model's relative mesh files are, as Drake's parser finds them: the
    `<compiler>`'s `meshdir` (else its `assetdir`), against the model's folder unless
    absolute; the model's folder without either."""
    compiler = re.search(r"<compiler\b([^>]*)>", text)
    attributes = compiler.group(1) if compiler else ""
    found = (re.search(_ATTRIBUTE.format("meshdir"), attributes)
             or re.search(_ATTRIBUTE.format("assetdir"), attributes))
    return model_dir / found.group(1) if found else model_dir


def _check_model_mesh(mesh: Path, scale: str | None, what: str, path: str) -> None:
    try:
        if mesh.suffix.lower() in MESH_EXTENSIONS:
            check_mesh_file(mesh)
        else:  # a .vtk volume mesh, ...: Drake reads it whole
            sc.read_bytes(mesh, kind="a mesh file", max_bytes=MAX_MODEL_BYTES)
    except MeshFileError as e:
        raise DirectiveError(path, f"{what}: {e}") from None
    except sc.ScenarioError as e:
        raise DirectiveError(path, f"{what}: {e.message}") from None
    for value in (scale or "").split():
        try:
            problem = MESH_SCALE.problem(float(value))
        except ValueError:
            problem = f"not a number: {value!r}"
        if problem:
            raise DirectiveError(path, f"{what}: scale {problem}")


def _directive_paths(directives: list) -> dict[str, str]:
    """{model name: the field of the directive that adds it} (included files: the include)."""
    paths = {}
    for i, directive in enumerate(directives):
        if directive.add_model is not None:
            paths[directive.add_model.name] = f"directives[{i}].add_model"
        elif directive.add_directives is not None:
            paths[f"directives[{i}]"] = f"directives[{i}].add_directives"
    return paths


def _model_shapes(plant, scene_graph, added, paths: dict, rigid_on_ground: str
                  ) -> list[ModelShape]:
    context = plant.CreateDefaultContext()
    inspector = scene_graph.model_inspector()
    anchored = {b.index() for b in plant.GetBodiesWeldedTo(plant.world_body())}
    shapes = []
    for info in added:
        path = paths.get(info.model_name) or next(
            (p for key, p in paths.items() if key.startswith("directives[")), "directives")
        for index in plant.GetBodyIndices(info.model_instance):
            body = plant.get_body(index)
            name = f"{info.model_name}::{body.name()}"
            _check_inertia(plant, body, name, path, index in anchored)
            X_WB = plant.EvalBodyPoseInWorld(context, body)
            for gid in plant.GetCollisionGeometriesForBody(body):
                shape = inspector.GetShape(gid)
                props = inspector.GetProximityProperties(gid)
                rigid = (props.HasProperty("hydroelastic", "compliance_type")
                         and not props.HasProperty("hydroelastic", "hydroelastic_modulus"))
                if index not in anchored and rigid and not isinstance(shape, Sphere):
                    raise DirectiveError(path, f"{name}: a free body with a rigid "
                                         f"hydroelastic shape {rigid_on_ground}: make it "
                                         "compliant (drake:compliant_hydroelastic) or weld it")
                if isinstance(shape, HalfSpace):  # no start pose to check
                    continue
                if isinstance(shape, Mesh):  # checked above; placement uses its hull
                    shape = Convex(shape.source(), shape.scale3())
                shapes.append(ModelShape(name, path, shape, X_WB @ inspector.GetPoseInFrame(gid),
                                         index in anchored))
    return shapes


def _check_inertia(plant, body, name: str, path: str, anchored: bool) -> None:
    """A finite, non-negative mass and a physically valid inertia; a body that moves on a
    joint of its own needs mass, and one that turns freely its rotational inertia."""
    mass = body.default_mass()
    inertia = body.default_rotational_inertia().CopyToFullMatrix3()
    if not (np.isfinite(mass) and np.all(np.isfinite(inertia))):
        raise DirectiveError(path, f"{name}: its mass and inertia must be finite numbers")
    if mass < 0 or not body.default_spatial_inertia().IsPhysicallyValid():
        raise DirectiveError(path, f"{name}: a negative mass or an inertia no body has "
                             f"(mass {mass:g} kg; the moments must be >= 0 and obey the "
                             "triangle inequality)")
    if anchored:
        return
    joint = next((plant.get_joint(j) for j in plant.GetJointIndices(body.model_instance())
                  if plant.get_joint(j).child_body().index() == body.index()), None)
    moves = joint is None or joint.num_velocities() > 0
    if moves and mass <= 0:
        raise DirectiveError(path, f"{name}: a body that moves needs a mass > 0 (got {mass:g} "
                             "kg)")
    if body.is_floating_base_body() and not np.all(np.linalg.eigvalsh(inertia) > 0):
        raise DirectiveError(path, f"{name}: a free body needs a rotational inertia > 0 about "
                             "every axis")
