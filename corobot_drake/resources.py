"""Where the package's data lives: the robot model directory and the shipped scenarios.

`models/` and `scenarios/` sit at the repository's top level. The build configuration
(pyproject.toml, `package-dir`) copies them into a wheel as `corobot_drake/_models` and
`corobot_drake/_scenarios`; a source checkout or an editable install uses the repository's.
"""

from pathlib import Path

_PACKAGE_DIR = Path(__file__).resolve().parent


def _data_dir(name: str) -> Path:
    in_wheel = _PACKAGE_DIR / f"_{name}"
    return in_wheel if in_wheel.is_dir() else _PACKAGE_DIR.parent / name


MODELS_DIR = _data_dir("models")
"""The robot's SDFormat model, its Drake `package.xml` and `meshes/`."""

SCENARIOS_DIR = _data_dir("scenarios")
"""The shipped scenario files."""

DEFAULT_SCENARIO = SCENARIOS_DIR / "corobot.yaml"
"""The book chapter's scene: the robot at the origin facing +x, the giant box behind it."""
