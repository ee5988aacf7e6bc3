"""What every ROS 2 participant of the project shares, without Drake: where discovery reaches,
rclpy's classes by type name, messages as plain data."""

from __future__ import annotations

import importlib
import os

DISCOVERY_VARIABLE = "ROS_AUTOMATIC_DISCOVERY_RANGE"
ARRAY_SHOWN = 16
"""Values of an array printed in full (`as_data`); longer ones (an image) are summarized."""


def configure_discovery(network: bool = False, environ=os.environ) -> str:
    """Sets where DDS discovery reaches, before a node starts: `SUBNET` with `network`, else the
    user's ROS_AUTOMATIC_DISCOVERY_RANGE if set, else `LOCALHOST` (this machine only, as the
    HTTP server listens on loopback by default). Returns the range in force."""
    if network:
        environ[DISCOVERY_VARIABLE] = "SUBNET"
    else:
        environ.setdefault(DISCOVERY_VARIABLE, "LOCALHOST")
    return environ[DISCOVERY_VARIABLE]


def ros_type(name: str):
    """The rclpy class of `package/msg|srv|action/Name`."""
    package, kind, cls = name.split("/")
    return getattr(importlib.import_module(f"{package}.{kind}"), cls)


def as_data(msg):
    """A message as nested dicts, lists and numbers (long arrays summarized), for printing."""
    if hasattr(msg, "get_fields_and_field_types"):
        return {name: as_data(getattr(msg, name)) for name in msg.get_fields_and_field_types()}
    if isinstance(msg, list | tuple) or hasattr(msg, "tolist"):
        values = msg.tolist() if hasattr(msg, "tolist") else list(msg)
        if len(values) > ARRAY_SHOWN:
            return f"<{len(values)} values>"
        return [as_data(v) for v in values]
    if isinstance(msg, bytes):
        return f"<{len(msg)} bytes>"
    return msg
