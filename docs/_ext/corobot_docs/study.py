"""The study engine's metrics from their registry (`corobot_drake.study.metrics`): each
registered metric's name, unit, what it is (its function's docstring), whether it makes the
runs scan the sensors and the simulated time it needs."""

from __future__ import annotations

import inspect

from corobot_docs.markdown import cell, table


def metrics() -> str:
    from corobot_drake.study import metrics as registry

    rows = []
    for name, fn in registry.METRICS.items():
        doc = inspect.getdoc(fn)
        if not doc:
            raise ValueError(f"the metric {name!r} ({fn.__module__}.{fn.__name__}) has no "
                             "docstring to say what it is")
        rows.append([f"`{name}`", cell(registry.UNITS[name] or "text or mixed"), cell(doc),
                     "yes" if name in registry.READS_IR else "",
                     f"{registry.NEEDS_SECONDS[name]:g} s" if name in registry.NEEDS_SECONDS
                     else ""])
    return table(("metric", "unit", "what", "scans the sensors", "needs a run of"), rows)
