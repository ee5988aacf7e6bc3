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

def shipped_scenario(name: str, folder: str = "") -> Path | None:
    """The shipped file a bare file name names (`maze.yaml`; `folder="studies"` for the
    shipped studies), or None when `name` is a path or no such file ships."""
    shipped = SCENARIOS_DIR / folder / name
    return shipped if Path(name).name == name and shipped.is_file() else None


def scenario_path(name: str) -> Path:
    """The scenario file `name` names: a path as it is when it exists, else, for a bare file
    name, the shipped scenario of that name (`maze.yaml` from any folder, also from a wheel)."""
    path = Path(name)
    return path if path.exists() else shipped_scenario(name) or path


PACKAGE_XML = MODELS_DIR / "package.xml"
"""Drake's package file for `models/`: its `package://corobot_drake/...` URIs."""


def package_map():
    """Drake's default package map (`drake`, ...) with the project's `corobot_drake`."""
    from pydrake.multibody.parsing import PackageMap

    packages = PackageMap()
    packages.AddPackageXml(str(PACKAGE_XML))
    return packages


def make_parser(plant):
    """A Drake `Parser` into `plant` that knows Drake's packages and the project's."""
    from pydrake.multibody.parsing import Parser

    parser = Parser(plant)
    parser.package_map().AddPackageXml(str(PACKAGE_XML))
    return parser


def resolve_file(uri: str) -> str:
    """A filesystem path for a `package://` URI (through `package_map`) or a path (as is).
    RuntimeError for an unknown package."""
    return package_map().ResolveUrl(uri) if uri.startswith("package://") else uri
