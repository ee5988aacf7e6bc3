"""Models of your own in the world: Drake model directives (SDFormat files) and `!Mesh` world
bodies, seen by the IR sensors, the camera, the summary and Meshcat like any other body."""

import pytest
from pydrake.geometry import Role, StartMeshcat

from conftest import make_sim
from corobot_drake.config.scenario import ScenarioError, load_scenario
from corobot_drake.config.sensors import default_ir_sensors
from corobot_drake.resources import SCENARIOS_DIR
from corobot_drake.robots import robot_spec
from corobot_drake.simulation import Simulation

MAZE = SCENARIOS_DIR / "maze.yaml"
IR = default_ir_sensors()
"""The Corobot's IR sensors, as its robot file mounts them."""
SPEC = robot_spec("corobot")
EXACT_IR = 1e-6
"""m: the IR reading is an exact ray cast; a flat face square to the sensor is hit first by
the centre ray, so the reading is the distance to it up to rounding (the robot's yaw after a
straight drive, ~2e-5 rad, lengthens it by ~1e-10 m)."""


def box_face(sim, name: str, axis: int, side: float) -> float:
    """World coordinate (m) of one face of a box collision geometry, as SceneGraph has it:
    `axis` 0 x, 1 y; `side` -1 the low face, +1 the high one."""
    inspector = sim.station.scene_graph.model_inspector()
    query = sim.station.diagram.GetOutputPort("query_object").Eval(sim.context)
    (gid,) = [g for g in inspector.GetAllGeometryIds(Role.kProximity)
              if inspector.GetName(g).endswith(f"::{name}")]
    X_WG = query.GetPoseInWorld(gid)
    size = {0: inspector.GetShape(gid).width(), 1: inspector.GetShape(gid).depth()}[axis]
    return float(X_WG.translation()[axis] + side * size / 2)


def test_maze_ir_sees_the_directive_models_walls_while_driving():
    sim = make_sim("robots: {corobot: {commands: [!Wait {seconds: 0.5}, "
                   "!SetVelocity {linear: 0.3, angular: 0.0}, !Wait {seconds: 3.0}, "
                   "!AllStop {}]}}", scenario=MAZE)
    robot = sim.robot()
    sim.advance(0.3)  # at rest: a scan every 0.05 s
    # At the start the rear sensor sees the west wall, the front one nothing within range.
    rear_x = robot.pose().x - IR["front"].X_PB.translation[0]  # the rear sensor is as far back
    assert robot.ir("rear").raw == pytest.approx(rear_x - box_face(sim, "west", 0, +1),
                                                  abs=EXACT_IR)
    assert robot.ir("front").raw == IR["front"].maximum_range
    sim.advance(4.2)  # 3 s at 0.3 m/s, then stopped (for 1 s): ~0.9 m on, the wall in range
    front_x = robot.pose().x + IR["front"].X_PB.translation[0]
    expected = box_face(sim, "inner_a", 0, -1) - front_x
    assert 0.3 < expected < IR["front"].maximum_range  # the drive brought it into range
    assert robot.ir("front").raw == pytest.approx(expected, abs=EXACT_IR)
    assert robot.ir("rear").raw == IR["front"].maximum_range


def test_driving_into_a_maze_wall_stops_at_it():
    """The rigid hydroelastic walls against the compliant tyres: the robot pushes at full
    power, stays on the ground and upright, its front tyres against the wall (they stick out
    past the chassis)."""
    sim = make_sim(scenario=MAZE)
    robot = sim.robot()
    robot.set_power(1.0, 1.0)
    sim.advance(4.0)  # reaches the wall (1.2 m at 0.6 m/s) and pushes for ~2 s
    face = box_face(sim, "inner_a", 0, -1)
    # 2 mm: the tyre's compliant patch (measured 0.5 mm into the wall).
    assert robot.pose().x == pytest.approx(face - SPEC.wheelbase / 2 - SPEC.wheel_radius,
                                           abs=2e-3)
    assert robot.max_tilt_deg() < 5.0  # measured 2 deg: it neither climbs nor flips
    assert abs(robot.pose().z) < 1e-3


def test_maze_in_the_summary_camera_and_meshcat():
    meshcat = StartMeshcat()
    scenario = load_scenario(MAZE)
    sim = Simulation(scenario, meshcat)
    sim.advance(0.1)
    assert sim.summary()["bodies"]["maze::walls"]["pose"]["x"] == pytest.approx(0.5)  # the frame
    assert meshcat.HasPath("/drake/illustration/maze/walls")
    assert meshcat.HasPath("/drake/proximity/maze/walls")
    # The camera looks at the inner wall 1.45 m ahead: its centre is the wall's grey, where
    # the same view without the maze is sky blue.
    wall = sim.robot().camera_image()[120, 160, :3].astype(int)
    scenario.directives = []
    empty = Simulation(scenario)
    empty.advance(0.1)
    sky = empty.robot().camera_image()[120, 160, :3].astype(int)
    assert abs(wall[0] - wall[1]) < 10 and wall[2] < wall[0]  # grey, a little warm
    assert sky[2] - sky[0] > 50  # blue
    meshcat.Delete()


CUBE_OBJ = """v -0.5 -0.5 -0.5
v 0.5 -0.5 -0.5
v 0.5 0.5 -0.5
v -0.5 0.5 -0.5
v -0.5 -0.5 0.5
v 0.5 -0.5 0.5
v 0.5 0.5 0.5
v -0.5 0.5 0.5
vn 0 0 -1
vn 0 0 1
vn 0 -1 0
vn 1 0 0
vn 0 1 0
vn -1 0 0
f 1//1 3//1 2//1
f 1//1 4//1 3//1
f 5//2 6//2 7//2
f 5//2 7//2 8//2
f 1//3 2//3 6//3
f 1//3 6//3 5//3
f 2//4 3//4 7//4
f 2//4 7//4 6//4
f 3//5 4//5 8//5
f 3//5 8//5 7//5
f 4//6 1//6 5//6
f 4//6 5//6 8//6
"""

PILLAR_SDF = """<?xml version="1.0"?>
<sdf version="1.9">
  <model name="pillar">
    <link name="column">
      <collision name="column"><pose>0 0 0.25 0 0 0</pose>
        <geometry><cylinder><radius>0.1</radius><length>0.5</length></cylinder></geometry>
      </collision>
      <visual name="column"><pose>0 0 0.25 0 0 0</pose>
        <geometry><cylinder><radius>0.1</radius><length>0.5</length></cylinder></geometry>
      </visual>
    </link>
  </model>
</sdf>
"""


def test_relative_file_uri_and_a_mesh_body(tmp_path):
    """A `file://` model relative to the scenario (a cylinder in front of the robot) and a
    `!Mesh` OBJ cube relative to it too (behind): both read at their exact distances."""
    (tmp_path / "models").mkdir()
    (tmp_path / "models" / "pillar.sdf").write_text(PILLAR_SDF)
    (tmp_path / "models" / "cube.obj").write_text(CUBE_OBJ)
    scenario = tmp_path / "s.yaml"
    scenario.write_text("""
directives:
- add_model: {name: pillar, file: "file://models/pillar.sdf"}
- add_weld:
    parent: world
    child: pillar::column
    X_PC: {translation: [0.6, 0.0, 0.0]}
world:
  bodies:
    crate:
      shape: !Mesh {filename: models/cube.obj, scale: 0.4}
      fixed: true
      pose: {translation: [-0.7, 0.0, 0.2]}
    rock:                       # free: it falls and rests on its convex hull
      shape: !Mesh {filename: models/cube.obj, scale: 0.2}
      mass: 2.0
      pose: {translation: [0.0, 1.0, 0.5]}
robots:
  corobot: {cameras: {front: {rgb: false}}}
""")
    sim = Simulation(load_scenario(scenario))
    sim.advance(0.1)
    ir = sim.robot().ir_distances()
    front, rear = IR["front"].X_PB.translation[0], IR["rear"].X_PB.translation[0]
    # Centre rays square to the faces: the cylinder's nearest point and the cube's face.
    assert ir["front"] == pytest.approx(0.6 - 0.1 - front, abs=EXACT_IR)
    assert ir["rear"] == pytest.approx(rear - (-0.7 + 0.2), abs=EXACT_IR)
    sim.advance(1.5)
    bodies = sim.summary()["bodies"]
    assert set(bodies) == {"crate", "rock", "pillar::column"}
    # On the ground on a face: its centre half its 0.2 m size up (a 1e7 Pa compliant patch
    # under 20 N sinks well under a millimetre).
    assert bodies["rock"]["pose"]["z"] == pytest.approx(0.1, abs=1e-3)


@pytest.mark.parametrize("override, message", [
    ("directives: [{add_model: {name: m, file: 'package://corobot_drake/none.sdf'}}]",
     r"directives\[0\]\.add_model\.file: .*none\.sdf.* does not exist"),
    ("directives: [{add_model: {name: corobot, file: 'package://corobot_drake/maze.sdf'}}]",
     r"directives\[0\]\.add_model\.name: 'corobot' already names a robot"),
    ("directives: [{add_model: {name: m, file: 'package://corobot_drake/maze.sdf'}}, "
     "{add_weld: {parent: world, child: 'm::wall'}}]", r"directives: .*no Frame named 'wall'"),
    ("world: {bodies: {rock: {shape: !Mesh {filename: rock.stl}}}}",
     r"world\.bodies\.rock\.shape\.filename: .*a mesh file is one of \.obj"),
    ("world: {bodies: {rock: {shape: !Mesh {filename: 'package://corobot_drake/meshes/"
     "chassis.obj', scale: -1}}}}",
     r"world\.bodies\.rock\.shape\.scale: must be in \[0\.0001, 10000\]"),
    ("world: {bodies: {rock: {shape: !Mesh {filename: 'package://corobot_drake/meshes/"
     "chassis.obj', collision: mesh}, fixed: true}}}",
     r"world\.bodies\.rock\.shape\.collision: a surface mesh touches rigidly"),
])
def test_bad_models_stop_with_one_line(override, message):
    with pytest.raises(ScenarioError, match=rf"^--override:1: {message}"):
        load_scenario(MAZE, overrides=[override])


def test_directives_round_trip_through_a_saved_scenario(tmp_path):
    """The maze's directives save as they were; a free model (the pillar of the test above,
    unwelded, dropped) saves where it has come to rest."""
    (tmp_path / "pillar.sdf").write_text(PILLAR_SDF.replace(
        '<link name="column">', '<link name="column"><inertial><mass>1</mass></inertial>'))
    sim = make_sim(f"""directives:
- add_model: {{name: pillar, file: "file://{tmp_path}/pillar.sdf",
    default_free_body_pose: {{column: {{translation: [0.6, 0.5, 0.1]}}}}}}""", scenario=MAZE)
    sim.advance(1.0)
    rest = sim.summary()["bodies"]["pillar::column"]["pose"]
    assert rest["z"] == pytest.approx(0.0, abs=2e-3)  # fallen onto its base (point contact)
    path = tmp_path / "saved.yaml"
    sim.save_scenario(path)
    again = Simulation(load_scenario(path))
    assert [d.add_model.file for d in again.scenario.directives if d.add_model] == [
        f"file://{tmp_path}/pillar.sdf"]
    again_rest = again.summary()["bodies"]["pillar::column"]["pose"]
    assert [again_rest[k] for k in "xyz"] == pytest.approx([rest[k] for k in "xyz"], abs=1e-9)
