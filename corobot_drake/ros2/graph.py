"""What every ROS 2 participant of the project shares, without Drake: where discovery reaches,
rclpy's classes by type name, messages as plain data."""

from __future__ import annotations

import contextlib
import importlib
import os
import subprocess
import sys

DISCOVERY_VARIABLE = "ROS_AUTOMATIC_DISCOVERY_RANGE"
DISCOVERY_RANGES = ("LOCALHOST", "SUBNET", "OFF", "SYSTEM_DEFAULT")
"""The values rcl takes (exactly: another is warned about and taken as SUBNET)."""
STATIC_PEERS_VARIABLE = "ROS_STATIC_PEERS"
"""Addresses (`;`-separated) discovered beyond the range, under LOCALHOST too (not OFF)."""
DOMAIN_VARIABLE = "ROS_DOMAIN_ID"
MAX_DOMAIN_ID = 232
"""Fast DDS's highest domain id (its ports, 7400 + 250 per domain, must stay below 65536)."""
ARRAY_SHOWN = 16
"""Values of an array printed in full (`as_data`); longer ones (an image) are summarized."""


def configure_discovery(network: bool = False, environ=os.environ) -> str:
    """Sets where DDS discovery reaches, before a node starts: `SUBNET` with `network`, else the
    user's ROS_AUTOMATIC_DISCOVERY_RANGE if set (not empty), else `LOCALHOST` (this machine
    only, as the HTTP server listens on loopback by default). Returns the range in force
    (`environment_problem` has refused a value rcl would not take)."""
    if network:
        environ[DISCOVERY_VARIABLE] = "SUBNET"
    elif not environ.get(DISCOVERY_VARIABLE):
        environ[DISCOVERY_VARIABLE] = "LOCALHOST"
    return environ[DISCOVERY_VARIABLE]



def discovery_reach(discovery: str, environ=os.environ) -> tuple[str, list[str]]:
    """(where a node's discovery reaches, in words for its line; the warnings, one line each)
    for the range in force and ROS_STATIC_PEERS. Static peers are discovered over the network
    under LOCALHOST as under SUBNET (ROS 2's "Improved Dynamic Discovery" table); OFF
    discovers no node, static peers included."""
    peers = [p.strip() for p in environ.get(STATIC_PEERS_VARIABLE, "").split(";") if p.strip()]
    warnings = []
    if discovery in ("SUBNET", "SYSTEM_DEFAULT"):
        warnings.append(f"warning: ROS 2 discovery {discovery}: any ROS 2 node on the network "
                        "with this domain id can read the topics and drive the robot")
    if not peers:
        return discovery, warnings
    named = ", ".join(peers)
    if discovery == "OFF":
        return f"OFF ({STATIC_PEERS_VARIABLE} {named} unused: OFF discovers no node)", warnings
    warnings.append(f"warning: ROS 2 static peers {named} ({STATIC_PEERS_VARIABLE}) are reached "
                    "over the network: a ROS 2 node there with this domain id can read the "
                    "topics and drive the robot")
    return f"{discovery} and the static peers {named}", warnings

def environment_problem(environ=os.environ) -> str | None:
    """Why ROS 2's environment cannot be used as it stands (one line), else None: a
    ROS_DOMAIN_ID rcl or Fast DDS refuses (a traceback or an error per port otherwise), a
    ROS_AUTOMATIC_DISCOVERY_RANGE rcl does not know (it would warn and discover on the
    subnet, while the node said otherwise)."""
    domain = environ.get(DOMAIN_VARIABLE, "")
    if domain and not (domain.isdecimal() and domain.isascii()
                       and int(domain) <= MAX_DOMAIN_ID and (domain == "0" or domain[0] != "0")):
        return (f"{DOMAIN_VARIABLE}={domain}: must be a whole number in [0, {MAX_DOMAIN_ID}] "
                "(0-101 are clear of the ephemeral ports)")
    discovery = environ.get(DISCOVERY_VARIABLE, "")
    if discovery and discovery not in DISCOVERY_RANGES:
        return (f"{DISCOVERY_VARIABLE}={discovery}: must be one of {', '.join(DISCOVERY_RANGES)}"
                " (or unset: LOCALHOST)")
    return None


def refuse_unusable(program: str, environ=os.environ) -> None:
    """For a ROS 2 program of the project's (an example), before rclpy.init: when
    `environment_problem` has a line, "error: `program`: <it>" on stderr and exit status 2,
    before any DDS starts (rclpy would raise, or Fast DDS log an error per port); else
    nothing."""
    problem = environment_problem(environ)
    if problem:
        print(f"error: {program}: {problem}", file=sys.stderr)
        raise SystemExit(2)


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


class PrivateNetworkError(RuntimeError):
    """A private network namespace cannot be made here (not root, or no os.unshare)."""


@contextlib.contextmanager
def private_network():
    """The calling thread (and what it starts from then on: processes, DDS's threads) in a new
    network namespace with only loopback up, back in its own afterwards: DDS traffic cannot
    leave the machine. For tests and benchmarks; needs root (`unshare -n`): PrivateNetworkError
    otherwise."""
    if not hasattr(os, "unshare"):
        raise PrivateNetworkError("os.unshare needs Python 3.12 on Linux")
    original = os.open("/proc/self/ns/net", os.O_RDONLY)
    try:
        try:
            os.unshare(os.CLONE_NEWNET)
        except PermissionError:
            raise PrivateNetworkError("a private network namespace needs root (unshare -n)"
                                   ) from None
        subprocess.run(["ip", "link", "set", "lo", "up"], check=True)
        yield
    finally:
        os.setns(original, os.CLONE_NEWNET)
        os.close(original)
