"""The wheel: built from the checkout, installed (not editable) into a fresh virtual environment,
it runs the simulator from any directory, with its meshes and the default scenario; and every
third-party module the package, the tools, the tests and the examples import is a declared
dependency.

`test_the_installed_wheel_runs_from_any_directory` costs ~10 s (pip wheel, a venv, pip install,
a 1 s headless run on the core alone, a front end without its extra, then every module with
every extra) and is marked `wheel` (deselect with `-m "not wheel"`). How it gets the
dependencies without downloading them: the fresh venv is created without them, the wheel is
installed with `--no-deps`, and then the distributions the *wheel's own metadata* requires
(Requires-Dist, followed transitively, with extras and markers) are linked in from this
interpreter's environment, where `tools/setup` installed them: one symlink per top-level
entry of each distribution's RECORD, in a directory the venv reads through a `.pth` file.
Nothing else of this environment is visible there (not the editable install, not the dev
tools), so a missing declaration fails the run; `test_every_import_is_a_declared_dependency`
checks the imports the run does not reach, statically.
"""

from __future__ import annotations

import ast
import os
import re
import shutil
import subprocess
import sys
from importlib import metadata
from pathlib import Path

import pytest
from packaging.requirements import Requirement

from conftest import REPO
from corobot_drake.ros2.build import PACKAGES as BUILT_INTERFACES

tomllib = pytest.importorskip("tomllib")  # Python >= 3.11

COPY_IGNORE = shutil.ignore_patterns(".git", ".venv", "out", "build", "dist", "__pycache__",
                                     "*.egg-info", ".pytest_cache", ".ruff_cache")
DATA_DIRECTORIES = {"models": "corobot_drake._models", "scenarios": "corobot_drake._scenarios"}
"""The top-level directories that pyproject's package-dir maps into the package."""


def _pyproject() -> dict:
    return tomllib.loads((REPO / "pyproject.toml").read_text())


def _normalize(name: str) -> str:
    return re.sub(r"[-_.]+", "-", name).lower()


def _run(*args, **kwargs) -> subprocess.CompletedProcess:
    run = subprocess.run([str(a) for a in args], capture_output=True, text=True, **kwargs)
    assert run.returncode == 0, f"{args}:\n{run.stdout}\n{run.stderr}"
    return run


# --- the build configuration and the declared dependencies (fast) ---------------------------


def _directories_with_files(root: Path) -> list[Path]:
    return [d for d in [root, *root.rglob("*")] if d.is_dir() and d.name != "__pycache__"
            and any(f.is_file() for f in d.iterdir())]


def test_every_package_directory_is_listed_in_pyproject():
    """pyproject lists the packages (package-dir's data packages are not discoverable): a new
    subpackage, or a new directory in models/ or scenarios/, must be added there, or the wheel
    goes without it."""
    listed = set(_pyproject()["tool"]["setuptools"]["packages"])
    found = {".".join(d.relative_to(REPO).parts)
             for d in _directories_with_files(REPO / "corobot_drake")}
    for directory, package in DATA_DIRECTORIES.items():
        found |= {".".join((package, *d.relative_to(REPO / directory).parts))
                  for d in _directories_with_files(REPO / directory)}
    assert listed == found, (f"add to [tool.setuptools] packages: {sorted(found - listed)}; "
                             f"remove: {sorted(listed - found)}")


def _third_party_imports(*directories: str) -> dict[str, set[str]]:
    """{top-level module: files importing it} of the absolute imports that are neither the
    standard library, nor corobot_drake, nor a module of the directories (e.g. conftest), nor
    the docs site's extension (docs/_ext/corobot_docs, which the docs' tests import)."""
    local = {"corobot_drake", "lab", "corobot_docs",
             *(p.stem for d in directories for p in (REPO / d).rglob("*.py"))}
    out: dict[str, set[str]] = {}
    for directory in directories:
        for path in (REPO / directory).rglob("*.py"):
            for node in ast.walk(ast.parse(path.read_text())):
                if isinstance(node, ast.Import):
                    names = [alias.name for alias in node.names]
                elif isinstance(node, ast.ImportFrom) and node.level == 0:
                    names = [node.module]
                else:
                    continue
                for top in {name.split(".")[0] for name in names}:
                    if top not in sys.stdlib_module_names and top not in local:
                        out.setdefault(top, set()).add(str(path.relative_to(REPO)))
    return out


def _pinned_by(requirement: Requirement) -> set[str]:
    """The distributions a ROS 2 meta-package (`ros-jazzy-<pkg>`: the distro's pins of the
    real `ros-<pkg>` wheels) requires; none for any other."""
    if not _normalize(requirement.name).startswith("ros-jazzy-"):
        return set()
    requires = metadata.distribution(requirement.name).requires or []
    return {_normalize(Requirement(r).name) for r in requires}


def _declared(extra: str | None) -> set[str]:
    """The distributions the core (None) or an extra declares, self-references resolved
    (`corobot_drake[serve,...]`), a ROS 2 meta-package counting for the wheels it pins."""
    project = _pyproject()["project"]
    lines = project["dependencies"] if extra is None else project["optional-dependencies"][extra]
    out = set()
    for requirement in map(Requirement, lines):
        if _normalize(requirement.name) == _normalize(project["name"]):
            for inner in requirement.extras:
                out |= _declared(inner)
        else:
            out |= {_normalize(requirement.name), *_pinned_by(requirement)}
    return out


@pytest.mark.parametrize("directories, extras", [
    (("corobot_drake",), ("all",)),
    (("tools", "lab"), ("dev",)),
    (("tests", "examples"), ("dev",)),
], ids=["package", "tools and lab", "tests and examples"])
def test_every_import_is_a_declared_dependency(directories, extras):
    declared = _declared(None)
    for extra in extras:
        declared |= _declared(extra)
    distributions = metadata.packages_distributions()
    missing = {}
    # The ROS 2 interface packages no wheel ships: the project's own, built into the venv by
    # tools/setup for the [ros2] extra (which [all] and [dev] hold).
    built = set(BUILT_INTERFACES)
    for module, files in _third_party_imports(*directories).items():
        if module in built:
            continue
        names = {_normalize(d) for d in distributions.get(module, [module])}
        if not names & declared:
            missing[module] = sorted(files)
    assert not missing, f"imported but not declared in pyproject.toml: {missing}"


def test_every_extra_brings_the_modules_its_front_end_checks_for():
    """corobot_drake/extras.py names, per extra, the modules a front end checks for before it
    starts: the same extras as pyproject's, each module from a distribution of its extra."""
    from corobot_drake.extras import EXTRAS

    optional = _pyproject()["project"]["optional-dependencies"]
    assert set(EXTRAS) == set(optional) - {"all", "dev"}
    assert _declared("all") == set().union(*(_declared(e) for e in EXTRAS))
    distributions = metadata.packages_distributions()
    for extra, modules in EXTRAS.items():
        for module in modules:
            assert {_normalize(d) for d in distributions[module]} & _declared(extra), \
                (extra, module)


# --- the wheel itself (slow) ------------------------------------------------------------------


def _requirements_closure(requires: list[str], extras: tuple[str, ...] = ()
                          ) -> list[metadata.Distribution]:
    """The installed distributions `requires` (Requires-Dist lines) needs with `extras`,
    transitively (the project's own name, in a self-referencing extra, left out)."""
    found: dict[str, metadata.Distribution] = {}
    done: set[tuple[str, str]] = set()  # (distribution, extra) whose requirements are queued
    todo = [(Requirement(r), extra) for r in requires for extra in ("", *extras)]
    while todo:
        requirement, extra = todo.pop()
        if requirement.marker and not requirement.marker.evaluate({"extra": extra}):
            continue
        name = _normalize(requirement.name)
        if name == _normalize(_pyproject()["project"]["name"]):
            continue
        if name not in found:
            found[name] = metadata.distribution(requirement.name)
        for wanted in ("", *requirement.extras):
            if (name, wanted) not in done:
                done.add((name, wanted))
                todo += [(Requirement(line), wanted) for line in found[name].requires or []]
    return list(found.values())


def _link_distributions(distributions: list[metadata.Distribution], target: Path) -> None:
    """Symlinks every top-level file and directory of the distributions into `target`."""
    target.mkdir()
    for distribution in distributions:
        assert distribution.files, f"{distribution.metadata['Name']}: no RECORD"
        for top in {f.parts[0] for f in distribution.files}:
            if top in ("..", "__pycache__") or (target / top).exists():
                continue
            source = Path(distribution.locate_file(top))
            if source.exists():
                (target / top).symlink_to(source)


RUN_BY_NAME = """
import sys
from corobot_drake.cli import main
for name in sys.argv[1:]:  # one interpreter: the command line's own main, by name
    assert main([name, "--headless", "--duration", "0.1"]) in (0, None), name
"""
"""`python -m corobot_drake NAME --headless --duration 0.1` for each shipped scenario's name."""
IMPORT_EVERYTHING = """
import importlib, pkgutil, corobot_drake
for module in pkgutil.walk_packages(corobot_drake.__path__, "corobot_drake."):
    if not module.name.endswith("__main__"):  # that one runs the simulator
        try:
            importlib.import_module(module.name)
        except ModuleNotFoundError as e:  # the [ros2] extra's live node: rclpy and its messages
            if not (module.name == "corobot_drake.ros2.node" and e.name == "rclpy"):
                raise
from corobot_drake import resources as r
print(r.__file__, r.MODELS_DIR, r.DEFAULT_SCENARIO, sep="\\n")
"""
"""Imports every module of the installed package (each must find its dependencies; the live
ROS 2 node needs the [ros2] extra, which the wheel is installed without), then prints where
the package and its data are."""


@pytest.mark.wheel
def test_the_installed_wheel_runs_from_any_directory(tmp_path):
    source, dist, venv = tmp_path / "source", tmp_path / "dist", tmp_path / "venv"
    # A copy, so that the build's build/ and *.egg-info stay out of the checkout.
    shutil.copytree(REPO, source, ignore=COPY_IGNORE)
    _run(sys.executable, "-m", "pip", "wheel", ".", "--no-deps", "-w", dist, "--quiet",
         cwd=source)
    (wheel,) = dist.glob("corobot_drake-*.whl")
    _run(sys._base_executable, "-m", "venv", "--without-pip", venv)
    python = venv / "bin" / "python"
    _run(sys.executable, "-m", "pip", "--python", python, "install", "--no-deps", "--no-index",
         "--quiet", wheel)
    site = Path(_run(python, "-c", "import sysconfig; print(sysconfig.get_path('purelib'))")
                .stdout.strip())
    requires = metadata.Distribution.at(
        next(site.glob("corobot_drake-*.dist-info"))).requires or []
    assert not (site / "lab").exists() and not list(site.glob("lab-*")), "the wheel ships no lab"
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME")}

    # The core alone: a headless run works, a front end names its extra.
    _link_distributions(_requirements_closure(requires), tmp_path / "core")
    (site / "core.pth").write_text(f"{tmp_path / 'core'}\n")
    run = _run(python, "-m", "corobot_drake", "--headless", "--duration", "1",
               cwd=elsewhere, env=env, timeout=120)
    assert "simulated 1.00 s" in run.stdout
    served = subprocess.run([python, "-m", "corobot_drake", "--serve"], cwd=elsewhere, env=env,
                            capture_output=True, text=True, timeout=120)
    assert (served.returncode, served.stderr) == (
        2, "error: --serve needs the [serve] extra: pip install '.[serve]' in corobot-drake's "
           "clone or unpacked sdist (it is not on PyPI; tools/setup installs every extra)\n")
    gym = subprocess.run([python, "-c", "import corobot_drake.gym"], cwd=elsewhere, env=env,
                         capture_output=True, text=True, timeout=120)
    assert "corobot_drake.gym needs the [gym] extra" in gym.stderr.splitlines()[-1]

    # Every extra: every module imports.
    (everything,) = map(Requirement, _pyproject()["project"]["optional-dependencies"]["all"])
    extras = tuple(sorted(everything.extras))
    _link_distributions(_requirements_closure(requires, extras), tmp_path / "extras")
    (site / "extras.pth").write_text(f"{tmp_path / 'extras'}\n")
    where = _run(python, "-c", IMPORT_EVERYTHING, cwd=elsewhere, env=env).stdout.split()
    assert all(Path(p).is_relative_to(site / "corobot_drake") for p in where), where
    for installed, directory in ((Path(where[1]), "models"),
                                 (Path(where[2]).parent, "scenarios")):  # every file of them
        assert sorted(p.relative_to(installed) for p in installed.rglob("*") if p.is_file()) \
            == sorted(p.relative_to(REPO / directory) for p in (REPO / directory).rglob("*")
                      if p.is_file() and "__pycache__" not in p.parts), directory
    names = sorted(p.name for p in (REPO / "scenarios").glob("*.yaml"))  # each shipped one
    run = _run(python, "-c", RUN_BY_NAME, *names, cwd=elsewhere, env=env, timeout=300)
    assert run.stdout.count("simulated 0.10 s") == len(names), run.stdout
    assert sorted(p.name for p in elsewhere.iterdir()) == []  # nothing written there
