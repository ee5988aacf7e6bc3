"""Mesh files a scenario names, checked before Drake, Meshcat or a renderer reads them.

A world body's `!Mesh` and the meshes of the directives' models: OBJ, glTF (`.gltf` with its
buffers) or GLB. `check_mesh_file` reads at most MAX_MESH_BYTES of a regular file (a FIFO or a
device is refused unread, a larger file by its size), then counts its triangles (at most
MAX_MESH_TRIANGLES) and reads its vertices (finite) in this module's own small parsers; what
it returns is the mesh's bounding box, for the scale's check. Drake read a 1e6-triangle mesh
with 5.4 GB and for minutes, a sparse 512 MiB OBJ with 1.1 GB before refusing it, and `/dev/zero`
until it ran out of memory.
"""

import base64
import dataclasses as dc
import json
import math
import struct
from pathlib import Path

import numpy as np

from corobot_drake.config.schema import MESH_EXTENSIONS, ScenarioError, read_bytes
from corobot_drake.limits import SHAPE_SIZE

MAX_MESH_BYTES = 16 << 20
"""A mesh file's largest size, its glTF buffers included (16 MiB: an OBJ of ~150k triangles)."""
MAX_MESH_TRIANGLES = 100_000
"""A mesh's most triangles (the robot's whole look has 20k; Drake's convex hull, the
renderers and Meshcat each take the mesh whole)."""

_KIND = "a mesh is an OBJ, glTF or GLB file"
_GLTF_COMPONENTS = {5120: "b", 5121: "B", 5122: "h", 5123: "H", 5125: "I", 5126: "f"}
_GLB_MAGIC, _GLB_JSON, _GLB_BIN = b"glTF", 0x4E4F534A, 0x004E4942


@dc.dataclass(frozen=True)
class MeshInfo:
    """What a mesh file holds: its triangles and its vertices' bounding box (file units)."""

    triangles: int
    low: np.ndarray
    high: np.ndarray


class MeshFileError(ValueError):
    """A mesh file that cannot be used: `str()` says why, without the file's name."""


def check_mesh_file(path: str | Path, extensions=MESH_EXTENSIONS) -> MeshInfo:
    """`path`'s mesh, checked (module docstring), if its name ends in one of `extensions`;
    MeshFileError naming what is wrong."""
    suffix = Path(path).suffix.lower()
    if suffix not in extensions:
        raise MeshFileError("a mesh file is one of " + ", ".join(extensions) + " (any case)")
    data = _read(path, MAX_MESH_BYTES)
    if suffix == ".obj":
        return _obj(data)
    if suffix == ".glb":
        document, binary = _glb(data)
        return _gltf(document, Path(path).parent, binary, len(data))
    try:
        document = json.loads(data)
    except (ValueError, RecursionError) as e:
        raise MeshFileError(f"not a glTF file (not JSON: {str(e).splitlines()[0]})") from None
    return _gltf(document, Path(path).parent, None, len(data))


def mesh_source(uri: str):
    """What Drake's `Mesh` and `Convex` read for a scenario's mesh file `uri` (checked before):
    its path, or for a GLB the same glTF in memory, its binary chunk a data URI (Drake builds no
    convex hull from a GLB file, and does from a glTF), its other files read beside it."""
    from pydrake.common import MemoryFile
    from pydrake.geometry import InMemoryMesh

    from corobot_drake.resources import resolve_file

    path = Path(resolve_file(uri))
    if path.suffix.lower() != ".glb":
        return str(path)
    document, binary = _glb(_read(path, MAX_MESH_BYTES))
    beside = {}
    for buffer in document.get("buffers", []):
        if "uri" not in buffer:
            buffer["uri"] = ("data:application/octet-stream;base64,"
                             + base64.b64encode(binary or b"").decode())
    for item in [*document.get("buffers", []), *document.get("images", [])]:
        if "uri" in item and not item["uri"].startswith("data:"):
            beside[item["uri"]] = path.parent / item["uri"]
    return InMemoryMesh(mesh_file=MemoryFile(json.dumps(document).encode(), ".gltf", str(path)),
                        supporting_files=beside)


def _read(path, max_bytes: int) -> bytes:
    try:
        return read_bytes(path, kind=_KIND, max_bytes=max_bytes)
    except ScenarioError as e:
        raise MeshFileError(e.message) from None


def _budget(triangles: int) -> None:
    if triangles > MAX_MESH_TRIANGLES:
        raise MeshFileError(f"more than {MAX_MESH_TRIANGLES} triangles (the most a mesh may "
                            "have)")


def _bounds(vertices: np.ndarray, triangles: int) -> MeshInfo:
    if triangles == 0:
        raise MeshFileError("has no faces (a mesh needs triangles; a glTF's in a node)")
    if not np.all(np.isfinite(vertices)):
        raise MeshFileError("has a vertex that is not a finite number (NaN or infinite)")
    return MeshInfo(triangles, vertices.min(axis=0), vertices.max(axis=0))


def _obj(data: bytes) -> MeshInfo:
    """Wavefront OBJ: `v` vertices, `f` polygons (a polygon of n corners is n - 2 triangles),
    and the vertex normals (`vn`) the cameras' renderer needs."""
    vertices, triangles, normals = [], 0, False
    for number, line in enumerate(data.decode("utf-8", "replace").splitlines(), 1):
        words = line.split()
        if not words:
            continue
        if words[0] == "v":
            try:
                vertices.append([float(w) for w in words[1:4]])
            except ValueError:
                raise MeshFileError(f"line {number}: a vertex needs 3 numbers") from None
            if len(vertices[-1]) != 3:
                raise MeshFileError(f"line {number}: a vertex needs 3 numbers")
        elif words[0] == "vn":
            normals = True
        elif words[0] == "f":
            _obj_face(words[1:], len(vertices), number)
            triangles += len(words) - 3
            _budget(triangles)
    if triangles and not normals:
        raise MeshFileError("has no vertex normals (vn): the cameras' renderer needs them")
    return _bounds(np.array(vertices, dtype=float).reshape(-1, 3), triangles)


def _obj_face(corners: list[str], vertex_count: int, number: int) -> None:
    if len(corners) < 3:
        raise MeshFileError(f"line {number}: a face needs at least 3 vertices")
    for corner in corners:
        try:
            index = int(corner.split("/")[0])
        except ValueError:
            raise MeshFileError(f"line {number}: a face's vertex is not a number") from None
        if not (1 <= index <= vertex_count or -vertex_count <= index <= -1):
            raise MeshFileError(f"line {number}: a face names vertex {index}, which is not "
                                "defined before it")


def _glb(data: bytes) -> tuple[dict, bytes | None]:
    """A GLB's JSON document and its binary chunk (glTF 2.0, "GLB File Format")."""
    if len(data) < 20 or data[:4] != _GLB_MAGIC:
        raise MeshFileError("not a GLB file (no glTF binary header)")
    version, length = struct.unpack_from("<II", data, 4)
    if version != 2 or length != len(data):
        raise MeshFileError(f"not a glTF 2.0 binary file (version {version}, length {length} "
                            f"of {len(data)} bytes)")
    chunks, offset = {}, 12
    while offset + 8 <= len(data):
        size, kind = struct.unpack_from("<II", data, offset)
        if offset + 8 + size > len(data):
            raise MeshFileError("a GLB chunk runs past the end of the file")
        chunks.setdefault(kind, data[offset + 8:offset + 8 + size])
        offset += 8 + size
    if _GLB_JSON not in chunks:
        raise MeshFileError("a GLB file without its JSON chunk")
    try:
        document = json.loads(chunks[_GLB_JSON])
    except (ValueError, RecursionError):
        raise MeshFileError("a GLB file whose JSON chunk is not JSON") from None
    return document, chunks.get(_GLB_BIN)


def _gltf(document, directory: Path, binary: bytes | None, size: int) -> MeshInfo:
    """A glTF 2.0 document's triangles and POSITION vertices, its buffers read within the
    byte budget (`size`: the bytes read so far)."""
    try:
        if not str(document["asset"]["version"]).startswith("2"):
            raise MeshFileError("a glTF file of version 2.0 is needed")
        buffers = [_buffer(b, directory, binary) for b in document.get("buffers", [])]
        size += sum(len(b) for b in buffers)
        if size > MAX_MESH_BYTES:
            raise MeshFileError(f"larger than {MAX_MESH_BYTES >> 20} MiB with its buffers")
        triangles, vertices = 0, []
        drawn = {node["mesh"] for node in document.get("nodes", []) if "mesh" in node}
        for mesh in (document["meshes"][i] for i in sorted(drawn)):  # a node's, or unread
            for primitive in mesh["primitives"]:
                if primitive.get("mode", 4) != 4:  # points, lines, strips: no faces drawn so
                    continue
                if "NORMAL" not in primitive["attributes"]:
                    raise MeshFileError("a primitive has no vertex normals (NORMAL): the "
                                        "cameras' renderer needs them")
                positions = _accessor(document, buffers, primitive["attributes"]["POSITION"])
                index = primitive.get("indices")
                count = (document["accessors"][index]["count"] if index is not None
                         else len(positions))
                triangles += count // 3
                _budget(triangles)
                vertices.append(positions)
    except MeshFileError:
        raise
    except (KeyError, IndexError, TypeError, ValueError, AttributeError, struct.error) as e:
        raise MeshFileError(f"not a valid glTF 2.0 mesh ({type(e).__name__}: "
                            f"{str(e)[:80]})") from None
    return _bounds(np.concatenate(vertices) if vertices else np.zeros((0, 3)), triangles)


def _buffer(buffer: dict, directory: Path, binary: bytes | None) -> bytes:
    uri = buffer.get("uri")
    if uri is None:
        if binary is None:
            raise MeshFileError("a glTF buffer without data (no uri, no GLB binary chunk)")
        return binary
    if uri.startswith("data:"):
        return base64.b64decode(uri.split(",", 1)[1], validate=True)
    if "://" in uri or Path(uri).is_absolute():
        raise MeshFileError(f"a glTF buffer's uri {uri[:60]!r} must be a file beside it")
    return _read(directory / uri, MAX_MESH_BYTES)


def _accessor(document: dict, buffers: list[bytes], index: int) -> np.ndarray:
    """A POSITION accessor's vertices (VEC3 of floats), as an n x 3 array."""
    accessor = document["accessors"][index]
    if accessor["type"] != "VEC3" or accessor["componentType"] != 5126:
        raise MeshFileError("a glTF POSITION accessor must be VEC3 of floats")
    count = int(accessor["count"])
    if count < 0 or count > 3 * MAX_MESH_TRIANGLES:
        raise MeshFileError(f"a glTF accessor of {count} vertices")
    view = document["bufferViews"][accessor["bufferView"]]
    data = buffers[view["buffer"]]
    start = view.get("byteOffset", 0) + accessor.get("byteOffset", 0)
    stride = view.get("byteStride", 12)
    if count and (stride < 12 or start + stride * (count - 1) + 12 > min(
            len(data), view.get("byteOffset", 0) + view["byteLength"])):
        raise MeshFileError("a glTF accessor runs past its buffer")
    rows = np.ndarray(shape=(count, 3), dtype="<f4", buffer=data, offset=start,
                      strides=(stride, 4))
    return np.array(rows, dtype=float)


def scale_problem(info: MeshInfo, scale: float, scale_range) -> str | None:
    """Why `scale` does not suit the mesh (outside `scale_range`, or the scaled mesh larger or
    smaller than a shape may be), else None."""
    problem = scale_range.problem(scale)
    if problem:
        return problem
    extent = float(np.max(info.high - info.low)) * scale
    if not (SHAPE_SIZE.low <= extent <= SHAPE_SIZE.high) or not math.isfinite(extent):
        return (f"scaled, the mesh is {extent:.3g} m across; a shape's size must be in "
                f"[{SHAPE_SIZE.low:g}, {SHAPE_SIZE.high:g}] m")
    return None
