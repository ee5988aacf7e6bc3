"""What a model file reaches before Drake's parser reads it: its includes and its meshes.

Drake's parser follows a model's includes (SDFormat `<include><uri>`, MJCF
`<include file>`) and loads its meshes; a model that includes itself overflows its stack and a
mesh of gigabytes takes minutes. `model_problem` walks the model's text first and names
either in one line, so that nothing crashes or hangs.
"""

import math
import os
import re
from pathlib import Path

from corobot_drake.robots.spec import MAX_MESH_BYTES, MAX_MODEL_BYTES

MESH_SUFFIXES = (".obj", ".stl", ".dae", ".gltf", ".glb", ".vtk", ".ply", ".msh")
_INCLUDE_SDF = re.compile(r"<include\b[^>]*>.*?<uri>\s*([^<\s]+)\s*</uri>", re.S)
_INCLUDE_MJCF = re.compile(r"<include\b[^>]*\bfile\s*=\s*[\"']([^\"']+)[\"']")
_FILE_REFERENCE = re.compile(r"(?:<uri>\s*([^<\s]+)\s*</uri>|\b(?:filename|file)\s*=\s*"
                             r"[\"']([^\"']+)[\"'])")
MAX_INCLUDES = 64
"""Model files one model may reach through its includes."""


def _local(reference: str, directory: Path) -> Path | None:
    """The file a model's reference names, when it is one on this machine (relative,
    absolute, `file://` or the project's `package://`); None for what Drake resolves
    otherwise (`model://`, another package)."""
    from corobot_drake.resources import resolve_file

    if reference.startswith("file://"):
        reference = reference[len("file://"):]
    elif reference.startswith("package://"):
        try:
            reference = resolve_file(reference)
        except Exception:  # an unknown package: Drake's parser will say so
            return None
    elif "://" in reference:
        return None
    path = Path(reference)
    return path if path.is_absolute() else directory / path


def mib(size: int) -> str:
    """`size` bytes in MiB to one decimal, rounded up (a file one byte over a limit of 32 MiB
    reads "32.1 MiB", never "32 MiB")."""
    return f"{math.ceil(size * 10 / (1 << 20)) / 10:.1f} MiB"


def model_problem(model: Path) -> str | None:
    """A one-line problem with the files `model` reaches (an include cycle, too many
    includes, an included model or a mesh too large), or None."""
    chain, seen = [model.resolve()], set()
    return _walk(chain, seen)


def _walk(chain: list[Path], seen: set) -> str | None:
    path = chain[-1]
    seen.add(path)
    if len(seen) > MAX_INCLUDES:
        return f"reaches more than {MAX_INCLUDES} model files through its includes"
    try:
        size = os.path.getsize(path)
    except OSError:
        return None  # Drake's parser names a missing file
    if size > MAX_MODEL_BYTES:
        return (f"{path.name} is {mib(size)}; a model file may be at most "
                f"{MAX_MODEL_BYTES >> 20} MiB")
    text = path.read_text(errors="replace")
    for match in _FILE_REFERENCE.finditer(text):
        target = _local(match.group(1) or match.group(2), path.parent)
        if target is None or target.suffix.lower() not in MESH_SUFFIXES:
            continue
        mesh_size = os.path.getsize(target) if target.is_file() else 0
        if mesh_size > MAX_MESH_BYTES:
            return (f"the mesh {target.name} is {mib(mesh_size)}; a robot's mesh may be "
                    f"at most {MAX_MESH_BYTES >> 20} MiB")
    for match in (*_INCLUDE_SDF.finditer(text), *_INCLUDE_MJCF.finditer(text)):
        target = _local(match.group(1), path.parent)
        if target is None:
            continue
        if target.is_dir():
            target = target / "model.sdf"
        target = target.resolve()
        if target in chain:
            cycle = " -> ".join(p.name for p in [*chain[chain.index(target):], target])
            return f"includes itself ({cycle}); Drake's parser would never finish"
        if target.is_file() and target not in seen:
            problem = _walk([*chain, target], seen)
            if problem:
                return problem
    return None
