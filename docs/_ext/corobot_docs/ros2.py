"""The ROS 2 interface from the node's own tables: every module-level table of
`ros2.interfaces` (a tuple of its dataclasses: topics, actions, services, ...), the subscribed
topics it declares, /diagnostics (`ros2.diagnostics.TOPIC`), each sensor kind's topics
(`SensorKind.ros2_channels`) and the node's parameters (`ros2.parameters.PARAMETERS`)."""

from __future__ import annotations

import dataclasses as dc
import enum
import inspect

from corobot_docs.markdown import cell, docs_below, table


def _text(value) -> str:
    if isinstance(value, enum.Enum):
        return f"`{value.value}`"
    if isinstance(value, type):
        return f"`{value.__name__}`"
    if isinstance(value, bool):
        return "yes" if value else ""
    if isinstance(value, str) and value and " " not in value:
        return f"`{value}`"
    return cell(str(value))


def _tables(module):
    """(name, rows) of each module-level tuple of dataclass instances, in source order."""
    for name, value in vars(module).items():
        if name.isupper() and isinstance(value, tuple) and value \
                and all(dc.is_dataclass(v) and not isinstance(v, type) for v in value):
            yield name, value


def _dataclass_table(rows) -> str:
    fields = [f.name for f in dc.fields(rows[0])]
    return table(fields, [[_text(getattr(r, f)) for f in fields] for r in rows])


def _sensor_topics() -> str:
    from corobot_drake.sensors.registry import KINDS

    rows = []
    for kind in KINDS:
        for sub, (ros_type, qos) in kind.ros2_channels().items():
            topic = kind.topic_name("<sensor>") + (f"/{sub}" if sub else "")
            rows.append([f"`{kind.field}`", f"`{topic}`", f"`{ros_type}`", f"`{qos}`",
                         f"`{kind.frame_name('<sensor>')}`"])
    return table(("sensors", "topic", "type", "QoS", "frame"), rows)


def _pairs_of(module):
    """(name, (topic, ROS type)) of each module-level topic pair (a subscribed topic, the
    diagnostics')."""
    return [(name, value) for name, value in vars(module).items()
            if name.isupper() and isinstance(value, tuple) and len(value) == 2
            and all(isinstance(v, str) for v in value) and "/" in value[1]]


def _pairs(module) -> list[list[str]]:
    """Module-level (topic, ROS type) pairs (the subscribed topics) with their docstrings."""
    return [[f"`{value[0]}`", f"`{value[1]}`", cell(_doc_of(module, name))]
            for name, value in _pairs_of(module)]


def page() -> str:
    from corobot_drake.ros2 import interfaces

    out = [f"The node `{interfaces.NODE_NAME}`'s interface, generated at each build from "
           "`corobot_drake/ros2/interfaces.py` (`docs/_ext/corobot_docs/ros2.py`). Names are "
           "relative: with several robots each robot's are under its name, except the shared "
           "ones."]
    for name, rows in _tables(interfaces):
        doc = cell(_doc_of(interfaces, name))
        out.append(f"## {name.replace('_', ' ').capitalize()}\n\n"
                   + (f"{doc}\n\n" if doc else "") + _dataclass_table(rows))
    out.append("## Sensor topics\n\nOne per sensor, by kind (`sensors.registry.KINDS`); QoS "
               "names are `Qos`'s.\n\n" + _sensor_topics())
    from corobot_drake.ros2 import diagnostics

    pairs = _pairs(interfaces) + _pairs(diagnostics)
    if pairs:
        out.append("## Other topics\n\n" + table(("topic", "type", "what"), pairs))
    qos = [[f"`{q.value}`", cell(_doc_of_member(interfaces.Qos, q.name))]
           for q in interfaces.Qos] if hasattr(interfaces, "Qos") else []
    if qos:
        out.append("## QoS profiles\n\n" + table(("QoS", "what"), qos))
    out.append(_parameters())
    out.append(_simulation_interfaces())
    return "\n\n".join(out) + "\n"


def _parameters() -> str:
    """The node's ROS 2 parameters (`ros2.parameters.PARAMETERS`), as it declares them."""
    from corobot_drake.ros2 import parameters

    rows = []
    for p in parameters.PARAMETERS:
        if p.low is not None:
            allowed = f"{p.low:g} to {p.high:g} {p.unit}".rstrip()
        else:
            allowed = ", ".join(f"`{c}`" for c in p.choices) or f"a `{type(p.default).__name__}`"
        default = str(p.default).lower() if isinstance(p.default, bool) else f"{p.default}"
        rows.append([f"`{p.name}`", f"`{type(p.default).__name__}`", f"`{default}`", allowed,
                     "at start-up" if p.read_only else "any time", cell(p.what)])
    return ("## Parameters\n\n" + cell(parameters.__doc__.split("\n\n")[0]) + "\n\n"
            + table(("parameter", "type", "default", "allowed", "set", "what"), rows))


def _simulation_interfaces() -> str:
    """The ROS 2 Simulation Interfaces the node serves (`ros2.simulation_services`)."""
    from corobot_drake.ros2 import simulation_services as ss

    rows = [[f"`{name}`", "service", f"`{ss.PACKAGE}/srv/{srv}`"]
            for name, srv in ss.SERVICES.items()]
    rows.append([f"`{ss.ACTION[0]}`", "action", f"`{ss.PACKAGE}/action/{ss.ACTION[1]}`"])
    return ("## Simulation Interfaces\n\n" + cell(ss.__doc__.split("\n\n")[0]) + " "
            + cell(ss.FEATURES_INFO) + "\n\n" + table(("name", "kind", "type"), rows))


def _doc_of(module, name: str) -> str:
    return docs_below(module).get(name, "")


def _doc_of_member(cls, name: str) -> str:
    return docs_below(cls).get(name, "")


def default_robot() -> str:
    """The default scenario's node as its user sees it: every topic, action and service with
    its full name (the robot alone in its scenario: no namespace), from the same tables as
    `page` and the robot's own sensors."""
    from corobot_drake.config.scenario import load_scenario
    from corobot_drake.resources import DEFAULT_SCENARIO
    from corobot_drake.ros2 import diagnostics, interfaces
    from corobot_drake.sensors.registry import KINDS

    robot = next(iter(load_scenario(DEFAULT_SCENARIO).robots.values()))
    rows = [[f"`/{t.name}`", t.type, f"`{t.qos.value}`", cell(t.what)]
            for t in interfaces.TOPICS]
    for kind in KINDS:
        for name in getattr(robot, kind.field):
            topic = kind.topic_name(name)
            for sub, (ros_type, qos) in kind.ros2_channels().items():
                rows.append([f"`/{topic}/{sub}`" if sub else f"`/{topic}`", ros_type,
                             f"`{qos}`", cell(_sensor_topic_what(kind, name))])
    rows += [[f"`/{topic[0]}`", topic[1], "`reliable`", cell(_doc_of(diagnostics, name))]
             for name, topic in _pairs_of(diagnostics)]
    # The commands' rows (/cmd_vel among them) as the command table writes them.
    rows += [[c.strip() for c in row.strip("|").split(" | ")]
             for row in interfaces.command_rows()]
    return table(("name", "type", "QoS", "what"), rows)


def _sensor_topic_what(kind, sensor: str) -> str:
    """The kind's own words on its ROS 2 message (its `ros2_message`'s docstring where the kind
    writes one), and the frame the reading is in."""
    method = vars(type(kind)).get("ros2_message")
    words = inspect.getdoc(method) if method else inspect.getdoc(type(kind)).split(". ")[0]
    return f"the `{sensor}` {kind.field.rstrip('s').replace('_', ' ')}: {words} Frame " \
           f"`{kind.frame_name(sensor)}`."
