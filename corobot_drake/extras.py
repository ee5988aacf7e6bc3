"""The optional front ends and the pip extras that carry them.

The core (`pip install .` in a clone of the repository, or in an sdist `python -m build`
made; corobot-drake is not on PyPI) runs a scenario headless or in Meshcat; each front end
needs its extra (`pip install '.[serve]'`; `tools/setup` installs them all). A front end used
without it stops with one line naming the extra and how to install it (`install_hint`;
`--ros2` checks its own, with the interfaces `tools/setup` builds: `ros2/run.py`); so does a
tool of `tools/` (its imports of an extra's modules in a `try:` whose handler calls `exit_without`).
`tests/packaging/test_wheel.py` holds this table to pyproject's optional dependencies.
"""

import importlib.util
import sys
from typing import NoReturn

EXTRAS = {
    "serve": ("fastapi", "uvicorn", "httpx", "pydantic", "starlette", "fastapi_offline", "h11",
              "sse_starlette"),
    "study": ("ray", "tqdm", "matplotlib", "scipy"),
    "gym": ("gymnasium", "ray", "tqdm", "matplotlib"),
    "train": ("stable_baselines3", "ray"),  # and RLlib, in ray; both bring torch
    "record": ("foxglove", "websockets"),
    "ros2": ("rclpy", "rosbags"),
}
"""{extra: the top-level modules it brings}."""


def install_hint(*extras: str) -> str:
    """How to add `extras` to an installed corobot-drake, in one line: pip from the clone or
    the unpacked sdist (a `pip install 'corobot-drake[...]'` would ask PyPI, where the project
    is not)."""
    return (f"pip install '.[{','.join(extras)}]' in corobot-drake's clone or unpacked sdist "
            "(it is not on PyPI; tools/setup installs every extra)")


class MissingExtraError(ImportError):
    """A front end was used without its extra; the message is the one line to show."""


def missing_modules(extra: str) -> list[str]:
    """The modules of `extra` this environment cannot import."""
    return [m for m in EXTRAS[extra] if importlib.util.find_spec(m) is None]


def require(extra: str, what: str) -> None:
    """Raises MissingExtraError ("`what` needs the [extra] extra: pip install ...") unless every
    module of `extra` is importable."""
    if missing_modules(extra):
        raise MissingExtraError(f"{what} needs the [{extra}] extra: {install_hint(extra)}")


def exit_without(what: str, *extras: str) -> NoReturn:
    """For a program whose imports need `extras`, called in their `except ImportError:`: when
    one of them is missing, its one line on stderr ("error: `what` needs the [extra] extra:
    pip install ...") and exit status 2, not a traceback; else the ImportError being handled
    goes on (something else is missing)."""
    missing = [extra for extra in extras if missing_modules(extra)]
    if not missing:
        raise  # (called from the handler: the ImportError it handles)
    names = " and ".join(f"[{extra}]" for extra in missing)
    print(f"error: {what} needs the {names} extra{'s' if len(missing) > 1 else ''}: "
          f"{install_hint(*missing)}", file=sys.stderr)
    raise SystemExit(2)
