"""Writes the Corobot's visual meshes (OBJ + MTL + PNG) into --out (default: ./meshes).

Usage: python tools/make_meshes.py [--out DIR] [--check]

    python tools/make_meshes.py --out models/meshes   # regenerate the shipped meshes
    python tools/make_meshes.py --check               # are the shipped meshes current?

Prints each mesh's triangle count and the whole robot's total against the budget. With --check
nothing is written: it exits 1 if a file in --out (default: the shipped models/meshes) differs
from what would be written (the PNG texture by its pixels and palette, the others byte for
byte), or the robot is over its triangle budget.

The geometry is `corobot_drake/model/meshes.py`'s; trimesh writes the OBJ files (a development
dependency: only this tool writes them) and Pillow the PNG texture.
"""

import argparse
import importlib.util
import io
import sys
from pathlib import Path

import numpy as np
from PIL import Image

from corobot_drake.model import meshes

DIGITS = 6
"""Decimals of every OBJ number: positions to 1 um (as built), normals and UVs (built to 1e-5)
exactly."""


def obj_text(mesh: meshes.MeshBuilder) -> str:
    """The mesh as Wavefront OBJ text: one object per material (its `usemtl`), each distinct
    (position, normal, UV) corner one vertex, in the order first used."""
    import trimesh  # the [dev] extra's (main says so when it is missing)

    class KeepNormals(trimesh.Trimesh):
        """A Trimesh whose copies keep its vertex normals: trimesh holds them in its cache,
        which a plain copy (the Scene's export makes one) drops, then recomputes them from
        the faces."""

        def copy(self, include_cache: bool = True, include_visual: bool = True):
            return super().copy(include_cache=include_cache, include_visual=include_visual)

    scene = trimesh.Scene()
    for material, (positions, normals, uvs) in mesh.groups().items():
        corners = np.concatenate([positions, normals, uvs], axis=2).reshape(-1, 3, 8)
        index: dict[tuple, int] = {}
        faces = [[index.setdefault(tuple(c), len(index)) for c in tri] for tri in corners]
        table = np.array(list(index))
        m = mesh.materials[material]  # its colours tell trimesh's materials apart
        visual = trimesh.visual.TextureVisuals(uv=table[:, 6:], material=(
            trimesh.visual.material.SimpleMaterial(name=material, diffuse=[*m.kd, 1.0],
                                                   specular=[m.ks] * 3 + [1.0],
                                                   glossiness=m.ns)))
        scene.add_geometry(KeepNormals(vertices=table[:, :3], faces=faces,
                                       vertex_normals=table[:, 3:6], visual=visual,
                                       process=False), geom_name=material)
    text, _ = trimesh.exchange.obj.export_obj(  # its MTL aside: `MeshBuilder.mtl_text`'s
        scene, include_normals=True, include_texture=True, return_texture=True,
        mtl_name=f"{mesh.name}.mtl", digits=DIGITS,
        header=f"{meshes.HEADER[2:].strip()}\n# {mesh.triangle_count} triangles")
    used = [line.split()[1] for line in text.splitlines() if line.startswith("usemtl ")]
    if used != list(mesh.groups()):  # trimesh merges materials it cannot tell apart
        raise ValueError(f"{mesh.name}: materials {list(mesh.groups())} written as {used}")
    return text


def png_bytes(indices: np.ndarray, palette: list[tuple[int, int, int]]) -> bytes:
    """An 8-bit palette PNG of `indices` (rows x columns into `palette`)."""
    h, w = indices.shape
    image = Image.frombytes("P", (w, h), indices.astype(np.uint8).tobytes())
    image.putpalette([c for rgb in palette for c in rgb])
    out = io.BytesIO()
    image.save(out, format="PNG", optimize=False, compress_level=9)
    return out.getvalue()


def generate_files(built: dict[str, meshes.MeshBuilder] | None = None) -> dict[str, bytes]:
    """Every file to write, by file name, in a fixed order."""
    built = meshes.build_meshes() if built is None else built
    files: dict[str, bytes] = {}
    for name, mesh in built.items():
        files[f"{name}.obj"] = obj_text(mesh).encode("ascii")
        files[f"{name}.mtl"] = mesh.mtl_text().encode("ascii")
    files[meshes.TEXTURE_NAME] = png_bytes(*meshes.platform_texture())
    return files


def write_files(out_dir: Path, files: dict[str, bytes] | None = None) -> list[Path]:
    files = generate_files() if files is None else files
    out_dir.mkdir(parents=True, exist_ok=True)
    written = []
    for name, data in files.items():
        path = out_dir / name
        path.write_bytes(data)
        written.append(path)
    return written


def same_content(name: str, data: bytes, path: Path) -> bool:
    """Whether the file at `path` holds `data`: a PNG the same pixels and palette (its
    compressed bytes depend on the zlib Pillow was built with), any other file byte for byte."""
    if not path.is_file():
        return False
    if not name.endswith(".png"):
        return path.read_bytes() == data
    try:
        with Image.open(path) as there, Image.open(io.BytesIO(data)) as here:
            return (there.mode == here.mode and there.getpalette() == here.getpalette()
                    and np.array_equal(np.asarray(there), np.asarray(here)))
    except OSError:  # not a PNG Pillow can read
        return False


def stale_files(out_dir: Path, files: dict[str, bytes] | None = None) -> list[str]:
    """Names of the generated files that are missing from out_dir or differ from it."""
    files = generate_files() if files is None else files
    return [name for name, data in files.items()
            if not same_content(name, data, out_dir / name)]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                     formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    parser.add_argument("--out", type=Path, default=None,
                        help="output directory (None: ./meshes; with --check, the shipped "
                        "models/meshes)")
    parser.add_argument("--check", action="store_true",
                        help="write nothing; exit 1 if the files in --out are stale")
    args = parser.parse_args()
    if importlib.util.find_spec("trimesh") is None:
        print("error: tools/make_meshes.py needs trimesh, a development dependency: "
              "pip install '.[dev]' in corobot-drake's clone (or run tools/setup)", file=sys.stderr)
        return 2

    built = meshes.build_meshes()
    counts = meshes.triangle_counts(built)
    for name, count in counts.items():
        k = meshes.ROBOT_MESH_COUNTS[name]
        note = f"  (x{k} per robot)" if k > 1 else ""
        print(f"{name + '.obj':16s} {count:6d} triangles{note}")
    total = meshes.robot_triangle_total(counts)
    over = total > meshes.TRIANGLE_BUDGET
    print(f"{'robot total':16s} {total:6d} triangles (budget {meshes.TRIANGLE_BUDGET})"
          + ("  OVER BUDGET" if over else ""))

    files = generate_files(built)
    if args.check:
        args.out = args.out or meshes.MESH_DIR
        stale = stale_files(args.out, files)
        for name in stale:
            print(f"stale: {args.out / name}")
        if not stale:
            print(f"{args.out}: up to date ({len(files)} files)")
        return 1 if stale or over else 0
    for path in write_files(args.out or Path("meshes"), files):
        print(f"wrote {path}")
    return 1 if over else 0


if __name__ == "__main__":
    sys.exit(main())
