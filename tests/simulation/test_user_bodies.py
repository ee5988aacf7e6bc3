"""Bodies of the user's own: world bodies and the directives' models rest on the ground and
stay on it when the robot pushes them, at the coarsest and the default plant step; what the
contact model cannot hold, and every bad model or mesh file, stops the load with one line."""

import math
import os

import numpy as np
import pytest

from conftest import make_sim
from corobot_drake.config.mesh_files import MAX_MESH_BYTES, MAX_MESH_TRIANGLES
from corobot_drake.config.scenario import CENIC_PLANT, SAP_PLANT, ScenarioError, load_scenario
from corobot_drake.limits import MAX_TIME_STEP
from corobot_drake.simulation import Simulation
from mesh_samples import CORNERS, CUBE_OBJ, TRIANGLES, gltf

COARSEST = CENIC_PLANT % MAX_TIME_STEP
"""The default integrator (CENIC) at the coarsest step the scenario allows."""
PLANTS = pytest.mark.parametrize("plant", [COARSEST, CENIC_PLANT % 0.01, SAP_PLANT % MAX_TIME_STEP],
                                 ids=["cenic-20ms", "cenic-10ms", "sap-20ms"])
"""The coarsest allowed step and the default's, and SAP's coarsest: a rigid box sank through
the ground at both steps (at 1 ms it held)."""
SINK_TOLERANCE = 0.003
"""m: how far a 2 kg, 0.2 m compliant box may sink or rock into the ground while pushed (the
1e7 Pa patch under its weight is ~0.05 mm; pushed at 20 ms its lowest centre was 0.6 mm
down). A box that sinks as the rigid ones did loses 8 cm to 50 cm."""

CRATE_URDF = """<?xml version="1.0"?>
<robot name="crate">
  <link name="crate">
    <inertial><mass value="{mass}"/>
      <inertia ixx="{ixx}" ixy="0" ixz="0" iyy="0.0133" iyz="0" izz="0.0133"/></inertial>
    <collision><geometry>{geometry}</geometry>{contact}</collision>
  </link>
</robot>
"""
BOX = '<box size="0.2 0.2 0.2"/>'


def crate(tmp_path, mass="2.0", ixx="0.0133", geometry=BOX, contact="", name="crate.urdf"):
    """A 0.2 m, 2 kg URDF crate (no hydroelastic properties unless `contact`), its path."""
    path = tmp_path / name
    path.write_text(CRATE_URDF.format(mass=mass, ixx=ixx, geometry=geometry, contact=contact))
    return path


def crate_directive(path, x=0.5) -> str:
    return (f"directives: [{{add_model: {{name: crate, file: 'file://{path}', "
            f"default_free_body_pose: {{crate: {{translation: [{x}, 0.0, 0.1]}}}}}}}}]")


def lowest_height(sim: Simulation, body, seconds: float) -> tuple[float, float]:
    """The body's lowest centre height over `seconds` (sampled every 0.05 s) and its final x."""
    plant, lowest = sim.station.plant, math.inf
    end = sim.time + seconds
    while sim.time < end - 1e-9:
        sim.advance(0.05)
        X = plant.EvalBodyPoseInWorld(plant.GetMyContextFromRoot(sim.context), body)
        lowest = min(lowest, X.translation()[2])
    return lowest, X.translation()[0]


PUSH = "robots: {corobot: {commands: [!SetPower {left: 0.5, right: 0.5}]}}"


@PLANTS
def test_a_pushed_box_stays_on_the_ground(plant):
    """A compliant world box in front of the robot, pushed at power 0.5 for 3 s."""
    sim = make_sim(plant, PUSH,
                   "world: {bodies: {crate: {shape: !Box {size: [0.2, 0.2, 0.2]}, mass: 2.0, "
                   "pose: {translation: [0.5, 0.0, 0.1]}}}}")
    lowest, x = lowest_height(sim, sim.station.bodies["crate"], 3.0)
    # It was pushed: 13 mm in 3 s under CENIC at 10-20 ms, 39 mm under SAP at 10 ms (at 1-2 ms
    # either pushes it 0.31-0.33 m; at coarse steps the push stalls: docs/performance.md).
    assert x > 0.51
    assert lowest > 0.1 - SINK_TOLERANCE


@PLANTS
def test_a_pushed_urdf_crate_stays_on_the_ground(tmp_path, plant):
    """A model without hydroelastic properties: its free body touches as a world body does
    (compliant), not by point contact, which let it sink through the ground."""
    sim = make_sim(plant, PUSH,
                   crate_directive(crate(tmp_path)))
    body = sim.station.plant.GetBodyByName("crate", sim.station.models["crate"])
    lowest, _ = lowest_height(sim, body, 3.0)
    assert lowest > 0.1 - SINK_TOLERANCE


def test_a_mesh_body_rests_and_obj_in_capitals_loads(tmp_path):
    """A free `!Mesh` cube (convex hull, compliant) at rest at the coarsest step, its file
    named `.OBJ`; the camera on (the renderer reads the file too)."""
    (tmp_path / "CUBE.OBJ").write_text(CUBE_OBJ)
    sim = make_sim(COARSEST,
                   f"world: {{bodies: {{m: {{shape: !Mesh {{filename: '{tmp_path}/CUBE.OBJ'}}, "
                   "mass: 2.0, pose: {translation: [0.8, 0.8, 0.1]}}}}", camera=True)
    lowest, _ = lowest_height(sim, sim.station.bodies["m"], 2.0)
    assert lowest > 0.1 - SINK_TOLERANCE
    assert sim.robot().camera_image() is not None


@pytest.mark.parametrize("override, message", [
    ("world: {bodies: {b: {shape: !Box {size: [0.2, 0.2, 0.2]}, hydroelastic_modulus: 0, "
     "pose: {translation: [0.5, 0, 0.1]}}}}",
     r"world\.bodies\.b\.hydroelastic_modulus: a free rigid Box touches the rigid ground at a "
     r"single point .* give it a modulus"),
    ("world: {bodies: {giant_box: {hydroelastic_modulus: 0}}}",
     r"world\.bodies\.giant_box\.hydroelastic_modulus: a free rigid Box"),
    ("world: {bodies: {b: {mass: 20, hydroelastic_modulus: 1e4, shape: !Box {size: [0.2, 0.2, "
     "0.2]}, pose: {translation: [0.5, 0, 0.1]}}}}",
     r"world\.bodies\.b\.hydroelastic_modulus: too soft for its mass: it would sink ~49 mm"),
])
def test_bodies_the_contact_cannot_hold_are_refused(override, message):
    with pytest.raises(ScenarioError, match=rf"^--override:1: {message}"):
        make_sim(override)


def test_a_free_surface_mesh_is_refused_a_fixed_one_is_not(tmp_path):
    (tmp_path / "cube.obj").write_text(CUBE_OBJ)
    body = (f"world: {{bodies: {{m: {{shape: !Mesh {{filename: '{tmp_path}/cube.obj', "
            "collision: mesh}, hydroelastic_modulus: 0, pose: {translation: [0.8, 0.8, 0.1]}")
    with pytest.raises(ScenarioError, match=r"m\.shape\.collision: a surface mesh touches "
                       r"rigidly, and a free rigid body .* make the body fixed"):
        make_sim(body + "}}}")
    make_sim(body + ", fixed: true}}}")


def test_a_rigid_sphere_rolls_on_the_ground():
    """The one free rigid shape point contact holds: pushed, it rolls away on the ground."""
    sim = make_sim(COARSEST, PUSH,
                   "world: {bodies: {ball: {shape: !Sphere {radius: 0.1}, "
                   "hydroelastic_modulus: 0, pose: {translation: [0.5, 0, 0.1]}}}}")
    lowest, x = lowest_height(sim, sim.station.bodies["ball"], 3.0)
    assert x > 0.6
    assert lowest > 0.1 - SINK_TOLERANCE


# --- the directives' models, checked as world bodies are ----------------------------------


@pytest.mark.parametrize("kwargs, message", [
    ({"mass": "0"}, r".*crate\.urdf:4: a mass or inertia no body has \(mass > 0 failed\)"),
    ({"mass": "-1"}, r".*crate\.urdf:4: a mass or inertia no body has \(mass > 0 failed\)"),
    ({"mass": "nan"}, r".*crate\.urdf:4: error: Expected single value for attribute 'value'"),
    ({"ixx": "nan"}, r".*crate\.urdf:5: error: Expected single value for attribute 'ixx'"),
    ({"ixx": "-0.1"}, r".*crate\.urdf:4: a mass or inertia no body has"),
    ({"ixx": "0"}, r"crate::crate: a free body needs a rotational inertia > 0 about every axis"),
    ({"contact": "<drake:proximity_properties><drake:rigid_hydroelastic/>"
      "</drake:proximity_properties>"}, r"crate::crate: a free body with a rigid hydroelastic "
     r"shape touches the rigid ground at a single point"),
])
def test_bad_model_bodies_are_refused(tmp_path, kwargs, message):
    with pytest.raises(ScenarioError, match=rf"^--override:1: directives(\[0\]\.add_model)?: "
                       rf"{message}"):
        load_scenario(None, overrides=[crate_directive(crate(tmp_path, **kwargs))])


def test_a_model_and_a_robot_may_not_start_inside_each_other(tmp_path):
    path = crate(tmp_path)
    with pytest.raises(ScenarioError, match=r"^--override:1: directives\[0\]\.add_model: robot "
                       r"'corobot' starts \d+ mm inside model body 'crate::crate'"):
        make_sim(crate_directive(path, x=0.1))
    with pytest.raises(ScenarioError, match=r"^--override:1: robots\.corobot\.pose: robot "
                       r"'corobot' starts \d+ mm inside model body 'crate::crate'"):
        make_sim(crate_directive(path, x=1.0),
                 "robots: {corobot: {pose: {translation: [0.95, 0, 0]}}}")


def test_a_set_pose_into_a_model_is_blocked_in_the_loaders_words(tmp_path):
    """The directives' models are obstacles to a SetPose as to a start pose: the same check
    (`placement.overlap_problems`) says the same thing about the same pose."""
    from corobot_drake.config.poses import ground_pose

    path = crate(tmp_path)
    sim = make_sim(crate_directive(path, x=1.0))
    X_WB = ground_pose(0.95, 0.0, 0.0).GetDeterministicValue()
    problem = sim.robot().obstacle_at(X_WB)
    assert problem.obstacle.name == "model body 'crate::crate'"
    with pytest.raises(ScenarioError) as refused:
        make_sim(crate_directive(path, x=1.0),
                 "robots: {corobot: {pose: {translation: [0.95, 0, 0]}}}")
    assert str(refused.value).endswith(f"robots.corobot.pose: {problem.message}")
    result = sim.robot().set_pose(0.95, 0.0, 0.0).wait(5)
    assert (result.status, result.reason) == ("failed", "blocked")


def special_files(tmp_path):
    fifo = tmp_path / "fifo.obj"
    os.mkfifo(fifo)
    zero = tmp_path / "zero.obj"
    zero.symlink_to("/dev/zero")
    return {"a FIFO": fifo, "a device": zero}


def test_special_model_and_mesh_files_are_refused_unread(tmp_path):
    """A FIFO with no writer (it would block) and /dev/zero (endless): refused at once."""
    for kind, path in special_files(tmp_path).items():
        with pytest.raises(ScenarioError, match=rf"directives\[0\]\.add_model\.file: {path}: "
                           rf"cannot read {kind}"):
            load_scenario(None, overrides=[
                f"directives: [{{add_model: {{name: m, file: 'file://{path}'}}}}]"])
        with pytest.raises(ScenarioError, match=rf"directives\[0\]\.add_model\.file: .*crate"
                           rf"\.urdf: mesh '{path}': cannot read {kind}"):
            load_scenario(None, overrides=[crate_directive(crate(
                tmp_path, geometry=f'<mesh filename="{path}"/>'))])
        with pytest.raises(ScenarioError, match=rf"world\.bodies\.m\.shape\.filename: {path}: "
                           rf"cannot read {kind}"):
            make_sim(f"world: {{bodies: {{m: {{shape: !Mesh {{filename: '{path}'}}}}}}}}")


def test_a_directives_file_that_includes_itself_is_refused(tmp_path):
    (tmp_path / "a.yaml").write_text(
        f"directives: [{{add_directives: {{file: 'file://{tmp_path}/b.yaml'}}}}]\n")
    (tmp_path / "b.yaml").write_text(
        f"directives: [{{add_directives: {{file: 'file://{tmp_path}/a.yaml'}}}}]\n")
    with pytest.raises(ScenarioError, match=r"directives\[0\]\.add_directives\.file: .*a\.yaml: "
                       r"a directives file includes itself \(a\.yaml -> b\.yaml -> a\.yaml\)"):
        load_scenario(None, overrides=[
            f"directives: [{{add_directives: {{file: 'file://{tmp_path}/a.yaml'}}}}]"])




def bad_meshes(tmp_path) -> dict:
    """{file name: (content, the error's text)}."""
    many = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\n" + "f 1 2 3\n" * (MAX_MESH_TRIANGLES + 1)
    nan = [[math.nan, 0, 0], *CORNERS[1:]]
    return {
        "nofaces.obj": ("v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\n", "has no faces"),
        "nan.obj": (CUBE_OBJ.replace("v -0.1 -0.1 -0.1", "v nan 0 0"), "not a finite number"),
        "many.obj": (many, f"more than {MAX_MESH_TRIANGLES} triangles"),
        "badindex.obj": ("v 0 0 0\nvn 0 0 1\nf 1 2 3\n", "a face names vertex 2"),
        "nonormals.obj": (CUBE_OBJ.replace("vn 0 0 1\n", "").replace("//1", ""),
                          r"no vertex normals \(vn\)"),
        "bad.gltf": (b"{not json", "not a glTF file"),
        "truncated.gltf": (gltf(CORNERS, TRIANGLES)[:-20] + b'"}]}', "not a glTF file"),
        "nan.gltf": (gltf(nan, TRIANGLES), "not a finite number"),
        "empty.glb": (gltf(CORNERS, [], glb=True), "has no faces"),
        "bad.glb": (b"glTF" + b"\0" * 30, "not a glTF 2.0 binary file"),
        "nan.glb": (gltf(nan, TRIANGLES, glb=True), "not a finite number"),
        "nonormals.gltf": (gltf(CORNERS, TRIANGLES, normals=False),
                           r"no vertex normals \(NORMAL\)"),
    }


def test_bad_meshes_are_refused_with_one_line(tmp_path):
    for name, (content, message) in bad_meshes(tmp_path).items():
        path = tmp_path / name
        (path.write_bytes if isinstance(content, bytes) else path.write_text)(content)
        with pytest.raises(ScenarioError, match=rf"world\.bodies\.m\.shape\.filename: {path}: "
                           rf".*{message}"):
            make_sim(f"world: {{bodies: {{m: {{shape: !Mesh {{filename: '{path}'}}}}}}}}")
        with pytest.raises(ScenarioError, match=rf"directives\[0\]\.add_model\.file: .*: mesh "
                           rf"'{path}': .*{message}"):
            load_scenario(None, overrides=[crate_directive(crate(
                tmp_path, geometry=f'<mesh filename="{path}"/>'))])


@pytest.mark.parametrize("name", ["cube.gltf", "CUBE.GLB"])
def test_a_good_gltf_or_glb_mesh_loads_rests_and_is_seen(tmp_path, name):
    """A free glTF or GLB cube (convex hull, compliant) rests, and the camera renders it (Drake
    hulls no GLB file: the station hands it over as glTF in memory)."""
    (tmp_path / name).write_bytes(gltf(CORNERS, TRIANGLES, glb=name.lower().endswith(".glb")))
    sim = make_sim(f"world: {{bodies: {{m: {{shape: !Mesh {{filename: '{tmp_path}/{name}'}}, "
                   "pose: {translation: [0.5, 0, 0.1]}}}}", camera=True)
    empty = make_sim(camera=True)
    sim.advance(0.5)
    empty.advance(0.5)
    assert sim.summary()["bodies"]["m"]["pose"]["z"] == pytest.approx(0.1, abs=1e-3)
    seen = np.any(sim.robot().camera_image() != empty.robot().camera_image(), axis=-1)
    assert seen.mean() > 0.05  # the cube fills part of the view ahead


def test_a_models_glb_collision_is_refused_and_its_glb_visual_said_to_go_unseen(tmp_path,
                                                                               caplog):
    """Drake hulls no GLB file, so a model's GLB collision mesh is refused; its cameras'
    renderer draws no GLB visual (Meshcat does), and Drake's warning saying so gets through."""
    (tmp_path / "c.glb").write_bytes(gltf(CORNERS, TRIANGLES, glb=True))
    mesh = f'<mesh filename="{tmp_path}/c.glb"/>'
    with pytest.raises(ScenarioError, match=rf"directives\[0\]\.add_model\.file: .*crate\.urdf: "
                       rf"mesh '{tmp_path}/c\.glb': a collision mesh is one of \.obj, \.gltf"):
        load_scenario(None, overrides=[crate_directive(crate(tmp_path, geometry=mesh))])
    with_visual = crate(tmp_path, name="visual.urdf")
    with_visual.write_text(with_visual.read_text().replace(
        "<collision>", f"<visual><geometry>{mesh}</geometry></visual><collision>"))
    sim = make_sim(crate_directive(with_visual), camera=True)
    assert sim.station.models["crate"] is not None
    assert any("RenderEngineGl" in r.getMessage() and "ignored" in r.getMessage()
               for r in caplog.records if r.name == "drake")


def test_a_surface_mesh_that_is_not_obj_is_refused(tmp_path):
    (tmp_path / "cube.gltf").write_bytes(gltf(CORNERS, TRIANGLES))
    with pytest.raises(ScenarioError, match=r"world\.bodies\.m\.shape\.collision: a surface "
                       r"mesh .* read from an OBJ file"):
        make_sim(f"world: {{bodies: {{m: {{shape: !Mesh {{filename: '{tmp_path}/cube.gltf', "
                 "collision: mesh}, fixed: true, hydroelastic_modulus: 0}}}")


def test_a_large_sparse_mesh_is_refused_by_its_size_unread(tmp_path):
    path = tmp_path / "huge.obj"
    with open(path, "wb") as f:
        f.truncate(512 << 20)  # sparse: no disk used
    with pytest.raises(ScenarioError, match=rf"{path}: the file is larger than "
                       rf"{MAX_MESH_BYTES >> 20} MiB"):
        make_sim(f"world: {{bodies: {{m: {{shape: !Mesh {{filename: '{path}'}}}}}}}}")


@pytest.mark.parametrize("scale, message", [
    ("1e-5", r"scale: must be in \[0\.0001, 10000\]"),
    ("1000", r"scale: scaled, the mesh is 200 m across"),
])
def test_a_mesh_scale_outside_its_range_is_refused(tmp_path, scale, message):
    (tmp_path / "cube.obj").write_text(CUBE_OBJ)
    with pytest.raises(ScenarioError, match=rf"world\.bodies\.m\.shape\.{message}"):
        make_sim(f"world: {{bodies: {{m: {{shape: !Mesh {{filename: '{tmp_path}/cube.obj', "
                 f"scale: {scale}}}}}}}}}")


MJCF_CRATE = """<mujoco model="crate">
  <compiler {compiler}/>
  <asset><mesh name="cube" file="cube.obj"/></asset>
  <worldbody>
    <body name="crate" pos="0.6 0.6 0.1">
      <freejoint/>
      <inertial pos="0 0 0" mass="2" diaginertia="0.0133 0.0133 0.0133"/>
      <geom type="mesh" mesh="cube"/>
    </body>
  </worldbody>
</mujoco>
"""


@pytest.mark.parametrize("compiler, folder", [('meshdir="meshes"', "meshes"),
                                              ('assetdir="assets"', "assets"),
                                              ('meshdir="meshes" assetdir="assets"', "meshes")])
def test_an_mjcf_model_finds_its_meshes_where_its_compiler_says(tmp_path, compiler, folder):
    """MJCF's `<compiler meshdir>` (else `assetdir`) names the meshes' folder: the checks
    look there, as Drake's parser does, and find a bad mesh there too."""
    (tmp_path / folder).mkdir()
    (tmp_path / folder / "cube.obj").write_text(CUBE_OBJ)
    model = tmp_path / "crate.xml"
    model.write_text(MJCF_CRATE.format(compiler=compiler))
    directive = f"directives: [{{add_model: {{name: crate, file: 'file://{model}'}}}}]"
    scenario = load_scenario(None, overrides=[directive])
    sim = Simulation(scenario)
    sim.advance(0.3)
    crate = sim.station.plant.GetBodyByName("crate")
    z = sim.station.plant.EvalBodyPoseInWorld(
        sim.station.plant.GetMyContextFromRoot(sim.context), crate).translation()[2]
    assert z == pytest.approx(0.1, abs=SINK_TOLERANCE)  # on the ground: the cube was found
    (tmp_path / folder / "cube.obj").write_text(bad_meshes(tmp_path)["nan.obj"][0])
    with pytest.raises(ScenarioError, match=r"directives\[0\]\.add_model\.file: .*: mesh "
                       r"'cube\.obj': .*not a finite number"):
        load_scenario(None, overrides=[directive])
