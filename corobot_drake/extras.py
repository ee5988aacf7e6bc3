"""The optional front ends and the pip extras that carry them.

The core (`pip install corobot-drake`) runs a scenario headless or in Meshcat; each front end
needs its extra. A front end used without it stops with one line naming the extra (`--ros2`
checks its own, with the interfaces `tools/setup` builds: `ros2/run.py`).
`tests/packaging/test_wheel.py` holds this table to pyproject's optional dependencies.
"""

import importlib.util

EXTRAS = {
    "serve": ("fastapi", "uvicorn", "httpx", "pydantic", "starlette", "fastapi_offline", "h11",
              "sse_starlette"),
    "study": ("ray", "tqdm", "matplotlib", "scipy"),
    "gym": ("gymnasium", "ray", "tqdm", "matplotlib"),
    "record": ("foxglove", "websockets"),
    "ros2": ("rclpy", "rosbags"),
}
"""{extra: the top-level modules it brings}."""


class MissingExtraError(ImportError):
    """A front end was used without its extra; the message is the one line to show."""


def missing_modules(extra: str) -> list[str]:
    """The modules of `extra` this environment cannot import."""
    return [m for m in EXTRAS[extra] if importlib.util.find_spec(m) is None]


def require(extra: str, what: str) -> None:
    """Raises MissingExtraError ("`what` needs the [extra] extra: pip install ...") unless every
    module of `extra` is importable."""
    if missing_modules(extra):
        raise MissingExtraError(f"{what} needs the [{extra}] extra: "
                           f"pip install 'corobot-drake[{extra}]'")
