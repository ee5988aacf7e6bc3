"""Pieces of the Python API page that follow the code's registries."""

from __future__ import annotations

ELSEWHERE = ("corobot_drake.readings",)
"""Modules the page documents whole (a reading there is not documented twice)."""


def sensor_readings() -> str:
    """An autodoc block for each registered kind's reading type."""
    from corobot_drake.sensors.registry import KINDS

    blocks = []
    for kind in KINDS:
        tp = kind.reading_type
        note = f"`{kind.field}`: `{tp.__module__}.{tp.__qualname__}`"
        if tp.__module__ in ELSEWHERE:
            blocks.append(f"- {note} (above)")
            continue
        blocks.append(f"- {note}\n\n  ```{{eval-rst}}\n  .. autoclass:: {tp.__module__}."
                      f"{tp.__qualname__}\n     :members:\n  ```")
    return "\n".join(blocks)
