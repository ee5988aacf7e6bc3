"""The docs site's generated reference: a Sphinx extension.

A page holds a marker line `<!-- reference: NAME -->`; when Sphinx reads the page, the marker
is replaced by the Markdown that `GENERATORS[NAME]` makes from the code (so nothing generated
is kept in the repository, and each build reads the code as it is).
"""

from __future__ import annotations

import re

MARKER = re.compile(r"^<!-- reference: (\w+) -->$", re.MULTILINE)


def _generators():
    from corobot_docs import benchmarks, cli, http, python, ros2, scenario, study

    return {"scenario": scenario.page, "cli": cli.page, "http": http.page, "ros2": ros2.page,
            "sensor_readings": python.sensor_readings, "benchmarks": benchmarks.page,
            "study_metrics": study.metrics,
            "ros2_default_robot": ros2.default_robot}


def _fill(app, docname: str, source: list[str]) -> None:
    generators = _generators()

    def replace(match):
        name = match.group(1)
        if name not in generators:
            raise ValueError(f"{docname}: no reference named {name!r}; "
                             f"there are {', '.join(generators)}")
        return generators[name]()

    source[0] = MARKER.sub(replace, source[0])


def setup(app):
    from corobot_docs import docstrings, pydrake_system

    app.connect("source-read", _fill)
    app.connect("autodoc-process-docstring", docstrings.process)
    app.connect("object-description-transform", docstrings.describe_fields)
    app.add_directive("pydrake_system", pydrake_system.PydrakeSystem)
    return {"parallel_read_safe": True, "parallel_write_safe": True, "version": "1"}
