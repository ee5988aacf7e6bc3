"""Small mesh files for the tests: a 0.2 m cube as OBJ text and as glTF or GLB bytes."""

import base64
import json

import numpy as np

CUBE_OBJ = "\n".join(
    [f"v {x} {y} {z}" for x in (-0.1, 0.1) for y in (-0.1, 0.1) for z in (-0.1, 0.1)]
    + ["vn 0 0 1"]
    + [f"f {a}//1 {b}//1 {c}//1" for a, b, c in (
        (1, 2, 4), (1, 4, 3), (5, 7, 8), (5, 8, 6), (1, 5, 6), (1, 6, 2),
        (3, 4, 8), (3, 8, 7), (1, 3, 7), (1, 7, 5), (2, 6, 8), (2, 8, 4))]) + "\n"
"""A 0.2 m cube centred on its origin."""


def gltf(vertices, indices, glb=False, normals=True) -> bytes:
    """A glTF 2.0 mesh of `vertices` (n x 3), each with a normal pointing away from the origin
    (unless not `normals`), and triangle `indices`: JSON with its buffer in a data URI, or GLB."""
    vertices = np.asarray(vertices, "<f4")
    n, m = len(vertices), len(indices)
    directions = vertices / np.maximum(np.linalg.norm(vertices, axis=1, keepdims=True), 1e-9)
    blob = (vertices.tobytes() + directions.astype("<f4").tobytes()
            + np.asarray(indices, "<u2").tobytes())
    attributes = {"POSITION": 0, "NORMAL": 2} if normals else {"POSITION": 0}
    document = {
        "asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}], "meshes": [{"primitives": [
            {"attributes": attributes, "indices": 1}]}],
        "buffers": [{"byteLength": len(blob)}],
        "bufferViews": [{"buffer": 0, "byteLength": 12 * n},
                        {"buffer": 0, "byteOffset": 24 * n, "byteLength": 2 * m},
                        {"buffer": 0, "byteOffset": 12 * n, "byteLength": 12 * n}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": n, "type": "VEC3"},
                      {"bufferView": 1, "componentType": 5123, "count": m, "type": "SCALAR"},
                      {"bufferView": 2, "componentType": 5126, "count": n, "type": "VEC3"}]}
    if not glb:
        document["buffers"][0]["uri"] = ("data:application/octet-stream;base64,"
                                         + base64.b64encode(blob).decode())
        return json.dumps(document).encode()
    text = json.dumps(document).encode().ljust(-(-len(json.dumps(document)) // 4) * 4)
    blob = blob.ljust(-(-len(blob) // 4) * 4, b"\0")
    chunks = (len(text).to_bytes(4, "little") + b"JSON" + text
              + len(blob).to_bytes(4, "little") + b"BIN\0" + blob)
    return b"glTF" + (2).to_bytes(4, "little") + (12 + len(chunks)).to_bytes(4, "little") + chunks


CORNERS = [[x, y, z] for x in (-0.1, 0.1) for y in (-0.1, 0.1) for z in (-0.1, 0.1)]
TRIANGLES = [0, 1, 3, 0, 3, 2, 4, 6, 7, 4, 7, 5, 0, 4, 5, 0, 5, 1,
             2, 3, 7, 2, 7, 6, 0, 2, 6, 0, 6, 4, 1, 5, 7, 1, 7, 3]
