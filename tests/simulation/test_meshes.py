"""The generated visual meshes: reproducible, loadable in Drake, in budget, the right size."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from pydrake.geometry import (
    GeometryInstance,
    IllustrationProperties,
    Mesh,
    PerceptionProperties,
    ReadObjToTriangleSurfaceMesh,
    RenderEngineVtkParams,
    RenderLabel,
    SceneGraph,
)
from pydrake.math import RigidTransform, RotationMatrix
from pydrake.systems.framework import DiagramBuilder

from conftest import REPO, load_tool
from corobot_drake.config.sensors import default_camera_config
from corobot_drake.model import dimensions as dim
from corobot_drake.model import meshes
from corobot_drake.sensors.camera import make_vtk_engine
from corobot_drake.sensors.render import color_camera, look_at

TOLERANCE = 0.005
"""Visual and collision geometry agree in overall size within this (metres)."""
BACKGROUND = (204, 229, 255)
"""RenderEngineVtkParams' default background colour."""
CHASSIS_MOUNTED = ("chassis", "platform", "camera", "ir_front", "ir_rear", "standoffs")
make_meshes = load_tool("make_meshes")


def read_obj(path: Path):
    """(vertices, triangles as vertex-index triples, triangles' vertex normals, usemtl names)."""
    v, vn, tris, tri_normals, used = [], [], [], [], []
    for line in path.read_text().splitlines():
        parts = line.split()
        if not parts:
            continue
        if parts[0] == "v":
            v.append([float(x) for x in parts[1:4]])
        elif parts[0] == "vn":
            vn.append([float(x) for x in parts[1:4]])
        elif parts[0] == "usemtl":
            used.append(parts[1])
        elif parts[0] == "f":
            corners = [p.split("/") for p in parts[1:]]
            assert len(corners) == 3, "triangles only"
            tris.append([int(c[0]) - 1 for c in corners])
            tri_normals.append([int(c[2]) - 1 for c in corners])
    vn = np.array(vn)
    return np.array(v), np.array(tris), vn[np.array(tri_normals)], used


def corners_by_material(path: Path) -> dict[str, np.ndarray]:
    """{material: (n, 3, 8) corners [position, normal, UV]} of an OBJ file's triangles, in
    the file's order (its v, vn and vt indexed separately, as OBJ allows)."""
    v, vt, vn, out, current = [], [], [], {}, None
    for line in path.read_text().splitlines():
        parts = line.split()
        if not parts:
            continue
        if parts[0] in ("v", "vt", "vn"):
            {"v": v, "vt": vt, "vn": vn}[parts[0]].append([float(x) for x in parts[1:]])
        elif parts[0] == "usemtl":
            current = out.setdefault(parts[1], [])
        elif parts[0] == "f":
            corners = [[int(i) - 1 for i in p.split("/")] for p in parts[1:]]
            current.append([v[a] + vn[c] + vt[b] for a, b, c in corners])
    return {material: np.array(tris) for material, tris in out.items()}


@pytest.fixture(scope="module")
def files() -> dict[str, bytes]:
    return make_meshes.generate_files()


def test_generation_is_deterministic(files):
    assert make_meshes.generate_files() == files


def test_regenerated_files_are_the_committed_ones(tmp_path, files):
    """Byte for byte, the PNG texture aside: its pixels and palette (its compressed bytes
    depend on the zlib Pillow was built with)."""
    make_meshes.write_files(tmp_path, files)
    for name in files:
        committed = meshes.MESH_DIR / name
        assert committed.is_file(), (
            f"{committed} is not committed; run tools/make_meshes.py --out models/meshes")
        assert make_meshes.same_content(name, (tmp_path / name).read_bytes(), committed), (
            f"{name} is stale; run tools/make_meshes.py --out models/meshes")


def test_the_obj_files_hold_each_triangle_as_built():
    """trimesh writes a vertex per distinct (position, normal, UV) corner: read back, each
    material's triangles have the corners `MeshBuilder` built, in its order."""
    for name, mesh in meshes.build_meshes().items():
        written = corners_by_material(meshes.MESH_DIR / f"{name}.obj")
        built = mesh.groups()
        assert list(written) == list(built), name
        for material, (positions, normals, uvs) in built.items():
            np.testing.assert_array_equal(
                written[material], np.concatenate([positions, normals, uvs], axis=2))


def test_the_texture_is_a_palette_png_of_the_drawn_pixels():
    from PIL import Image

    indices, palette = meshes.platform_texture()
    with Image.open(meshes.MESH_DIR / meshes.TEXTURE_NAME) as image:
        assert image.format == "PNG" and image.mode == "P"
        np.testing.assert_array_equal(np.asarray(image), indices)
        assert image.getpalette()[:3 * len(palette)] == [c for rgb in palette for c in rgb]


def test_tool_check_flag(tmp_path):
    tool = [sys.executable, str(REPO / "tools" / "make_meshes.py")]
    ok = subprocess.run([*tool, "--check"], capture_output=True, text=True, cwd=REPO)
    assert ok.returncode == 0, ok.stdout + ok.stderr
    assert "robot total" in ok.stdout
    subprocess.run([*tool, "--out", str(tmp_path)], check=True, capture_output=True, cwd=REPO)
    (tmp_path / "wheel.mtl").write_text("tampered\n")
    stale = subprocess.run([*tool, "--check", "--out", str(tmp_path)], capture_output=True,
                           text=True, cwd=REPO)
    assert stale.returncode == 1
    assert "wheel.mtl" in stale.stdout


@pytest.mark.parametrize("name", list(meshes.ROBOT_MESH_COUNTS))
def test_mesh_loads_in_drake_with_its_materials(name):
    obj = meshes.MESH_DIR / f"{name}.obj"
    surface = ReadObjToTriangleSurfaceMesh(str(obj))
    _, tris, _, used = read_obj(obj)
    assert surface.num_triangles() == len(tris) > 0
    mtl = (meshes.MESH_DIR / f"{name}.mtl").read_text()
    defined = [line.split()[1] for line in mtl.splitlines() if line.startswith("newmtl")]
    assert set(used) == set(defined)
    for line in mtl.splitlines():
        if line.startswith("map_Kd"):
            assert (meshes.MESH_DIR / line.split()[1]).is_file()


def test_texture_decodes_to_the_generated_image():
    import matplotlib.image

    indices, palette = meshes.platform_texture()
    rgb = np.asarray(palette, dtype=np.uint8)[indices]
    img = matplotlib.image.imread(meshes.MESH_DIR / meshes.TEXTURE_NAME)
    if img.dtype != np.uint8:
        img = np.round(img * 255).astype(np.uint8)
    assert img.shape[:2] == (meshes.TEXTURE_SIZE[1], meshes.TEXTURE_SIZE[0])
    np.testing.assert_array_equal(img[:, :, :3], rgb)


def test_triangle_budget():
    counts = meshes.triangle_counts()
    for name, count in counts.items():
        _, tris, _, _ = read_obj(meshes.MESH_DIR / f"{name}.obj")
        assert len(tris) == count
    total = meshes.robot_triangle_total(counts)
    assert total < meshes.TRIANGLE_BUDGET == 20_000
    # The wheels get the largest share of the budget, as in the original model.
    assert counts["wheel"] == max(counts.values())


@pytest.mark.parametrize("name", list(meshes.ROBOT_MESH_COUNTS))
def test_winding_agrees_with_normals(name):
    """Counter-clockwise triangles seen from outside (Meshcat culls back faces)."""
    v, tris, normals, _ = read_obj(meshes.MESH_DIR / f"{name}.obj")
    p = v[tris]
    geometric = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    assert np.all(np.einsum("ij,ij->i", geometric, normals.sum(axis=1)) > 0.0)


def box_bounds(part: dim.BoxPart) -> tuple[np.ndarray, np.ndarray]:
    c, s = np.array(part.center), np.array(part.size)
    return c - s / 2, c + s / 2


@pytest.mark.parametrize(("name", "expected"), [
    ("chassis", box_bounds(dim.CHASSIS)),
    ("platform", box_bounds(dim.PLATFORM)),
    ("wheel", (-np.array([dim.WHEEL_RADIUS, dim.WHEEL_WIDTH / 2, dim.WHEEL_RADIUS]),
               np.array([dim.WHEEL_RADIUS, dim.WHEEL_WIDTH / 2, dim.WHEEL_RADIUS]))),
])
def test_visual_matches_collision_size(name, expected):
    v, _, _, _ = read_obj(meshes.MESH_DIR / f"{name}.obj")
    np.testing.assert_allclose(v.min(axis=0), expected[0], atol=TOLERANCE)
    np.testing.assert_allclose(v.max(axis=0), expected[1], atol=TOLERANCE)


def test_wheel_tyre_and_hub_radii():
    v, _, _, _ = read_obj(meshes.MESH_DIR / "wheel.obj")
    radius = np.hypot(v[:, 0], v[:, 2])
    assert radius.max() == pytest.approx(dim.WHEEL_RADIUS, abs=1e-5)
    # The tyre's bore sits on the hub at WHEEL_HUB_RADIUS.
    assert np.any(np.isclose(radius, dim.WHEEL_HUB_RADIUS, atol=1e-5))


def test_sensor_housings_sit_at_their_mounts():
    for name, mount in (("camera", dim.CAMERA), ("ir_front", dim.FRONT_IR),
                        ("ir_rear", dim.REAR_IR)):
        v, _, _, _ = read_obj(meshes.MESH_DIR / f"{name}.obj")
        centre = (v.min(axis=0) + v.max(axis=0)) / 2
        assert np.linalg.norm(centre[1:] - np.array(mount.position[1:])) < 0.01, name
        # Sticks out of the chassis end it is mounted on, in its look direction.
        forward = np.cos(mount.yaw)
        assert np.max(forward * v[:, 0]) > dim.CHASSIS.size[0] / 2


# ---- rendering ------------------------------------------------------------------------------


class Scene:
    """The whole robot's visual meshes in a SceneGraph with a VTK renderer."""

    def __init__(self):
        builder = DiagramBuilder()
        self.scene_graph = builder.AddSystem(SceneGraph())
        self.scene_graph.AddRenderer("vtk", make_vtk_engine(RenderEngineVtkParams()))
        source = self.scene_graph.RegisterSource("corobot_meshes")
        placements = [(name, RigidTransform()) for name in CHASSIS_MOUNTED]
        placements += [("wheel", RigidTransform(dim.wheel_center(w))) for w in dim.WHEEL_NAMES]
        for i, (name, X) in enumerate(placements):
            instance = GeometryInstance(X, Mesh(str(meshes.MESH_DIR / f"{name}.obj")),
                                        f"{name}_{i}")
            perception = PerceptionProperties()
            perception.AddProperty("label", "id", RenderLabel(i + 1))
            instance.set_perception_properties(perception)
            instance.set_illustration_properties(IllustrationProperties())
            self.scene_graph.RegisterAnchoredGeometry(source, instance)
        self.diagram = builder.Build()
        context = self.diagram.CreateDefaultContext()
        self.query = self.scene_graph.get_query_output_port().Eval(
            self.scene_graph.GetMyContextFromRoot(context))

    def render(self, X_WC: RigidTransform, width=320, height=240, fov_y_deg=40.0, near=0.01):
        camera = color_camera(width, height, fov_y_deg, near, far=10.0, name="vtk")
        image = self.query.RenderColorImage(camera, self.scene_graph.world_frame_id(), X_WC)
        return np.array(image.data[:, :, :3], dtype=np.int32)


@pytest.fixture(scope="module")
def scene() -> Scene:
    return Scene()


def colour_fraction(image, rgb, tol=40) -> float:
    return float(np.mean(np.all(np.abs(image - np.array(rgb)) <= tol, axis=2)))


def test_robot_renders_with_its_materials(scene):
    image = scene.render(look_at([0.55, 0.4, 0.35], [0.0, 0.0, 0.1]))
    robot = ~np.all(image == BACKGROUND, axis=2)
    assert robot.mean() > 0.1
    # No geometry fell back to the renderer's default orange: every mesh found its MTL.
    assert colour_fraction(image, (230, 115, 25), tol=30) < 0.001
    # Black tyres and the textured platform's green circuit boards are visible.
    assert colour_fraction(image, (10, 10, 10), tol=25) > 0.02
    assert colour_fraction(image, (24, 112, 52), tol=30) > 0.0002


def test_platform_texture_is_mapped_upright(scene):
    """Close-up of the left side: the battery (blue) is low, the board (green) above it."""
    _, _, z0, z1 = meshes.electronics_box()
    image = scene.render(look_at([0.0, 0.45, (z0 + z1) / 2], [0.0, 0.0, (z0 + z1) / 2]),
                         fov_y_deg=12.0)
    rows_blue = np.nonzero(np.all(np.abs(image - (28, 48, 112)) <= 30, axis=2))[0]
    rows_green = np.nonzero(np.all(np.abs(image - (24, 112, 52)) <= 30, axis=2))[0]
    assert len(rows_blue) > 2000 and len(rows_green) > 200
    assert np.median(rows_blue) > np.median(rows_green)  # image rows grow downwards


def test_robots_own_camera_does_not_see_the_robot(scene):
    """The camera and IR housings stay out of the camera's view frustum."""
    R_BC = RotationMatrix(np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]]))
    X_WC = RigidTransform(R_BC, dim.CAMERA.position)
    camera = default_camera_config()  # its image size and field of view
    image = scene.render(X_WC, camera.width, camera.height, camera.focal.y,
                         near=0.001)
    assert np.all(image == BACKGROUND)
