"""The docs site (docs/, Sphinx + MyST) builds with warnings as errors, loads nothing from the
network, checks its internal links, and its generated reference holds what the code declares:
every scenario field with its range, every command's --help, every HTTP path, every ROS 2
topic, action and service.

One build of the whole site per module (~10 s of CPU here; the generated pages are made in the
build's process: docs/_ext/corobot_docs)."""

import dataclasses as dc
import html
import importlib
import inspect
import re
import subprocess
import sys

import pytest

from conftest import REPO

DOCS = REPO / "docs"


def sphinx(source, out, *extra):
    """`sphinx -W --keep-going -b html` (quiet) of `source` into `out`: the finished process."""
    return subprocess.run([sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b",
                           "html", *extra, str(source), str(out)],
                          capture_output=True, text=True, cwd=REPO, timeout=600)


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    out = tmp_path_factory.mktemp("site")
    build = sphinx(DOCS, out, "-d", str(out / ".doctrees"))
    return out, build


def text(site, page: str, section: str | None = None) -> str:
    """A built page's text (or its section whose anchor is `section`, up to the next):
    tags removed, entities decoded, whitespace collapsed."""
    raw = (site[0] / page).read_text()
    if section is not None:
        raw = raw.split(f'<section id="{section}">', 1)[1].split("<section id=", 1)[0]
    raw = re.sub(r"<(script|style)\b.*?</\1>", "", raw, flags=re.S)
    return re.sub(r"\s+", " ", html.unescape(re.sub(r"<[^>]+>", " ", raw)))


def test_the_site_builds_with_warnings_as_errors(site):
    _, build = site
    assert build.returncode == 0, build.stderr[-3000:]
    assert build.stderr.strip() == ""


def test_no_page_loads_anything_from_the_network(site):
    """Offline: no script, stylesheet, image or font from http(s) (links to other sites are
    fine: they are not loaded)."""
    out, _ = site
    remote = re.compile(r"""<(?:script|img|iframe|source)\b[^>]*\bsrc=["']?(?:https?:)?//"""
                        r"""|<link\b[^>]*\bhref=["']?(?:https?:)?//"""
                        r"""|url\(\s*["']?(?:https?:)?//|@import\s+["']?(?:https?:)?//""")
    found = [f"{p.relative_to(out)}: {m.group(0)}"
             for p in sorted(out.rglob("*")) if p.suffix in (".html", ".css", ".js")
             for m in remote.finditer(p.read_text(errors="replace"))]
    assert found == []
    assert (out / "index.html").exists() and (out / "reference" / "scenario.html").exists()


def test_a_broken_internal_link_fails_the_build(tmp_path):
    """The site's configuration (-c docs) on two pages, one linking to a heading the other
    lacks: Sphinx reports it, so the site's build fails on a broken link."""
    source = tmp_path / "src"
    source.mkdir()
    (source / "index.md").write_text("# Home\n\n```{toctree}\nother\n```\n\n"
                                     "[there](other.md#a-heading) and [gone](other.md#nowhere)\n")
    (source / "other.md").write_text("# Other\n\n## A heading\n\ntext\n")
    build = sphinx(source, tmp_path / "out", "-c", str(DOCS))
    assert build.returncode != 0
    problems = [line for line in build.stderr.splitlines() if "WARNING" in line]
    assert len(problems) == 1 and "nowhere" in problems[0], build.stderr


def test_the_scenario_reference_has_every_sensor_field_with_its_range(site):
    """Every field of every registered sensor kind's config, with its range in words
    (`Range.text`), as the loader states it."""
    from corobot_drake.limits import OneOf, Range
    from corobot_drake.sensors.registry import KINDS

    for kind in KINDS:
        if not dc.is_dataclass(kind.config_type):
            continue  # Drake's CameraConfig: its bounds are checked below
        section = text(site, "reference/scenario.html", kind.config_type.__name__.lower())
        for f in dc.fields(kind.config_type):
            assert f" {f.name} " in section, f"{kind.field}: {f.name}"
            bound = f.metadata.get("bound")
            if isinstance(bound, Range):
                assert bound.text() in section, f"{kind.field}.{f.name}: {bound.text()}"
            elif isinstance(bound, OneOf):
                assert all(n in section for n in bound.names)


def test_the_scenario_reference_has_drakes_structs_with_their_bounds(site):
    from corobot_drake.config.bounds import DRAKE_BOUNDS
    from corobot_drake.limits import Range

    for cls, bounds in DRAKE_BOUNDS.items():
        anchor = re.sub(r"[^a-z0-9]+", "-", cls.__qualname__.lower())  # docutils' ids
        section = text(site, "reference/scenario.html", anchor)
        for name, bound in bounds.items():
            assert f" {name} " in section
            if isinstance(bound, Range):
                assert bound.text() in section, f"{cls.__qualname__}.{name}"


def test_the_scenario_reference_has_the_robot_files_fields_with_their_ranges(site):
    """The robot file (`robots.file.RobotFile` and its structs), after the scenario's tables,
    every field with its range in words; its sensor maps link to the scenario's configs."""
    from corobot_drake.limits import Range
    from corobot_drake.robots.file import RobotFile

    top = text(site, "reference/scenario.html", "robotfile")
    for f in dc.fields(RobotFile):
        assert f" {f.name} " in top, f.name
    structs = [f for f in dc.fields(RobotFile) if f.name in ("wheels", "drive", "tyres",
                                                             "casters")]
    assert len(structs) == 4
    for f in structs:
        cls = type(getattr(RobotFile(), f.name))
        section = text(site, "reference/scenario.html", cls.__name__.lower())
        for inner in dc.fields(cls):
            assert f" {inner.name} " in section, f"{cls.__name__}.{inner.name}"
            bound = inner.metadata.get("bound")
            if isinstance(bound, Range):
                assert bound.text() in section, f"{cls.__name__}.{inner.name}: {bound.text()}"
    page = (site[0] / "reference" / "scenario.html").read_text()
    assert page.index('id="the-robot-file"') > page.index('id="bumperconfig"')


def test_every_command_has_its_help(site):
    page = text(site, "reference/cli.html")
    commands = ["python -m corobot_drake", "python -m corobot_drake.study",
                "python -m corobot_drake.ros2", "python -m corobot_drake.ros2.build",
                "python -m corobot_drake.robot"]
    commands += [f"python {folder}/{p.name}" for folder in ("tools", "examples")
                 for p in sorted((REPO / folder).glob("*.py"))]
    for command in commands:
        assert f"usage: {command} " in page, command
    assert "--headless" in page and "--workers" in page
    setup = subprocess.run(["bash", "tools/setup", "--help"], capture_output=True, text=True,
                           cwd=REPO, timeout=60, check=True).stdout
    assert "Usage: tools/setup" in setup and " ".join(setup.split()) in page


def test_the_http_reference_has_every_path_and_method(site, monkeypatch):
    monkeypatch.syspath_prepend(str(DOCS / "_ext"))
    from corobot_docs.http import openapi

    page = text(site, "reference/http.html")
    for path, operations in openapi()["paths"].items():
        for method in operations:
            assert f"{method.upper()} {path}" in page, f"{method} {path}"


def test_the_ros2_reference_has_every_topic_action_and_service(site):
    from corobot_drake.ros2 import interfaces
    from corobot_drake.sensors.registry import KINDS

    page = text(site, "reference/ros2.html")
    names = [t.name for t in interfaces.TOPICS] + [a.name for a in interfaces.ACTIONS] \
        + [s.name for s in interfaces.SERVICES]
    names += [kind.topic_name("<sensor>") + (f"/{sub}" if sub else "")
              for kind in KINDS for sub in kind.ros2_channels()]
    from corobot_drake.ros2 import diagnostics, simulation_services

    names += [*simulation_services.SERVICES, simulation_services.ACTION[0], diagnostics.TOPIC[0]]
    assert [n for n in names if f" {n} " not in page] == []
    assert f" {diagnostics.TOPIC[1]} " in page


def test_the_ros2_reference_has_every_parameter_with_its_range(site):
    """Each parameter the node declares, with its type, default and allowed values."""
    from corobot_drake.ros2.parameters import PARAMETERS

    section = text(site, "reference/ros2.html", "parameters")
    rows = {p.name: section.split(f" {p.name} ", 1)[-1][:400] for p in PARAMETERS}
    for p in PARAMETERS:
        assert f" {p.name} " in section, p.name
        row = rows[p.name]
        default = str(p.default).lower() if isinstance(p.default, bool) else str(p.default)
        assert row.startswith(f"{type(p.default).__name__} {default} "), (p.name, row[:80])
        allowed = [f"{p.low:g} to {p.high:g}"] if p.low is not None else list(p.choices)
        assert all(a in row for a in allowed), (p.name, allowed)
        assert p.what.split(" (")[0][:40] in row, p.name


def test_the_python_reference_documents_the_api(site):
    """autodoc's entries (their anchors: the objects' full names): the API's classes and
    functions, each kind's reading too, every field of the robot file and every method a
    sensor kind may override."""
    from corobot_drake.sensors.kind import SensorKind
    from corobot_drake.sensors.registry import KINDS

    page = (site[0] / "reference" / "python.html").read_text()
    names = ["corobot_drake.simulation.Simulation", "corobot_drake.simulation.Robot",
             "corobot_drake.simulation.Robot.drive_distance",
             "corobot_drake.robot_api.commands.CommandHandle",
             "corobot_drake.commands.SetVelocity", "corobot_drake.serving.client.CorobotClient",
             "corobot_drake.serving.client.RemoteRobot",
             "corobot_drake.serving.client.RemoteCommandHandle",
             "corobot_drake.config.scenario.load_scenario",
             "corobot_drake.gym.env.GoToGoalEnv", "corobot_drake.gym.env.GoToGoalEnv.step",
             "corobot_drake.gym.rollouts.rollouts", "corobot_drake.gym.rollouts.summary",
             "corobot_drake.gym.load_policy",
             "corobot_drake.recording.mcap_log.McapLog", "corobot_drake.robots.robot_spec",
             "corobot_drake.robots.spec.RobotSpec", "corobot_drake.robots.file.RobotFile",
             "corobot_drake.sensors.kind.SensorKind", "corobot_drake.sensors.kind.BuiltSensor",
             "corobot_drake.sensors.registry.KINDS",
             "corobot_drake.robot_api.sensors.IrSensors.ir",
             "corobot_drake.robot_api.sensors.Cameras.camera_image",
             "corobot_drake.systems.odometry.DriveState",
             "corobot_drake.systems.odometry.TwoWheelDriveState",
             "corobot_drake.resources.scenario_path", "corobot_drake.study.engine.run_study",
             "corobot_drake.study.engine.ray_session", "corobot_drake.study.metrics.RobotRun",
             "corobot_drake.gym.layout.Layout",
             "corobot_drake.recording.foxglove_live.FoxgloveLive",
             "corobot_drake.serving.runner.SimRunner", "corobot_drake.serving.webapp.create_app"]
    import corobot_drake.robots.file as robot_file

    names += [f"corobot_drake.robots.file.RobotFile.{f.name}"
              for f in dc.fields(robot_file.RobotFile)]
    names += [f"corobot_drake.sensors.kind.SensorKind.{name}"
              for name, value in vars(SensorKind).items()
              if not name.startswith("_") and (callable(value) or isinstance(value, property))]
    names += [f"{k.reading_type.__module__}.{k.reading_type.__qualname__}" for k in KINDS]
    assert [n for n in names if f'id="{n}"' not in page] == []


def _documented(name: str):
    """The object whose full name is `name` (a module's, or an attribute's of one), or None
    (a dataclass field without a default is no attribute of its class)."""
    parts = name.split(".")
    for i in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:i]))
        except ImportError:
            continue
        for part in parts[i:]:
            obj = getattr(obj, part, None)
        return obj
    return None


def undocumented_members(page: str, source: str) -> list[str]:
    """What the built Python reference (`page`, its HTML) leaves out of what it documents:
    each public member (inspect) of each class it documents, from the class and its bases in
    the package (`Robot`'s parts; not `object`'s, Gymnasium's), a dataclass' fields in its
    signature; and each public class and function of a module that `source` (the page's
    Markdown) documents whole (`automodule` with every `:members:`)."""
    missing = []
    ids = set(re.findall(r'id="(corobot_drake\.[\w.]+)"', page))
    for name in sorted(ids):
        cls = _documented(name)
        if not inspect.isclass(cls) or not cls.__module__.startswith("corobot_drake"):
            continue
        if (inspect.isclass(_documented(name.rpartition(".")[0]))
                and f"{cls.__module__}.{cls.__qualname__}" != name):
            continue  # a class attribute naming another class (`config_type`): its own entry
        start = page.index(f'id="{name}"')
        signature = page[start:page.index("</dt>", start)]
        fields = {f.name for f in dc.fields(cls)} if dc.is_dataclass(cls) else set()
        members = fields | {m for base in cls.__mro__
                            if base.__module__.startswith("corobot_drake") for m in vars(base)}
        for member in sorted(members):
            if member.startswith("_") or f"{name}.{member}" in ids:
                continue
            if member in fields and f'<span class="pre">{member}</span>' in signature:
                continue
            missing.append(f"{name}.{member}")
    for module in re.findall(r"^\.\. automodule:: (\S+)\n {3}:members:\n", source, re.M):
        missing += [f"{module}.{n}" for n, v in vars(importlib.import_module(module)).items()
                    if not n.startswith("_") and (inspect.isclass(v) or inspect.isfunction(v))
                    and v.__module__ == module and f"{module}.{n}" not in ids]
    return sorted(set(missing))


def test_the_python_reference_has_every_public_member_of_what_it_documents(site):
    """Every method, property and attribute of each class on the page (walked with inspect:
    a member without a docstring is dropped by autodoc, so this fails), and every class and
    function of the modules it documents whole (the HTTP client, the rollouts)."""
    page = (site[0] / "reference" / "python.html").read_text()
    source = (DOCS / "reference" / "python.md").read_text()
    assert undocumented_members(page, source) == []
    from corobot_drake.gym import rollouts
    from corobot_drake.serving import client
    from corobot_drake.simulation import Robot

    whole = re.findall(r"^\.\. automodule:: (\S+)\n {3}:members:\n", source, re.M)
    assert {client.__name__, rollouts.__name__} <= set(whole)
    assert "pose" in dir(Robot) and 'id="corobot_drake.simulation.Robot.pose"' in page


def test_the_member_check_finds_what_a_page_leaves_out():
    """The check on pages of the test's: the Robot documented without `pose` (a method of
    one of its parts), a dataclass without a field in its signature, and a module documented
    whole without one of its functions."""
    from corobot_drake.simulation import Robot

    robot = "corobot_drake.simulation.Robot"
    members = {m for base in Robot.__mro__ if base.__module__.startswith("corobot_drake")
               for m in vars(base) if not m.startswith("_")}
    assert "pose" in members and "ir_distances" in members
    page = (f'<dt id="{robot}">Robot</dt>'
            + "".join(f'<dt id="{robot}.{m}"></dt>' for m in members if m != "pose")
            + '<dt id="corobot_drake.readings.OdometryPose"><em class="sig-param"><span '
              'class="n"><span class="pre">x</span></span></em> y</dt>'
            + '<dt id="corobot_drake.gym.rollouts.rollouts"></dt>')
    source = ".. automodule:: corobot_drake.gym.rollouts\n   :members:\n"
    missing = undocumented_members(page, source)
    assert f"{robot}.pose" in missing
    assert "corobot_drake.readings.OdometryPose.y" in missing
    assert "corobot_drake.readings.OdometryPose.x" not in missing
    assert "corobot_drake.gym.rollouts.summary" in missing
    assert "corobot_drake.gym.rollouts.rollouts" not in missing


def api_names(markdown: str) -> set[str]:
    """The package's names a page writes in its code (fenced blocks and inline code): each
    `corobot_drake.<module>.<Name>[.<member>]` and each name a `from corobot_drake.<module>
    import ...` line imports, as its full name; not a module (`python -m corobot_drake.ros2`),
    not a private name (a part with a leading underscore)."""
    fence = r"^(```+|~~~+)[^\n]*\n(.*?)^\1"
    code = [block for _, block in re.findall(fence, markdown, flags=re.M | re.S)]
    prose = re.sub(fence, "", markdown, flags=re.M | re.S)
    code += [span for _, span in re.findall(r"(`+)(.+?)\1", prose, flags=re.S)]
    names = set()
    for snippet in code:
        names.update(re.findall(r"\bcorobot_drake(?:\.\w+)+", snippet))
        for module, imported in re.findall(r"^\s*from\s+(corobot_drake[\w.]*)\s+import\s+"
                                           r"(\([^)]*\)|[^\n#]+)", snippet, flags=re.M):
            for item in imported.strip("() \\").split(","):
                name = item.split(" as ")[0].strip(" \\\n")
                names |= {f"{module}.{name}"} if name else set()
    source = REPO.joinpath
    return {n for n in names if not any(part.startswith("_") for part in n.split("."))
            and not source(*n.split(".")).with_suffix(".py").is_file()
            and not source(*n.split("."), "__init__.py").is_file()}


def unreferenced(names, page: str) -> list[str]:
    """Those of `names` the built Python reference (`page`, its HTML) has no entry for,
    under the name as written or the object's own (`__module__`.`__qualname__`)."""
    missing = []
    for name in sorted(names):
        obj = _documented(name)
        own = f"{getattr(obj, '__module__', '')}.{getattr(obj, '__qualname__', '')}"
        if f'id="{name}"' not in page and f'id="{own}"' not in page:
            missing.append(name)
    return missing


def test_every_name_a_page_writes_is_in_the_python_reference(site):
    """Every package name a page of the site (not the reference's own) writes in its code,
    `corobot_drake.<module>.<Name>` or imported from one, has its entry in the reference."""
    page = (site[0] / "reference" / "python.html").read_text()
    named = {p.name: api_names(p.read_text()) for p in sorted(DOCS.glob("*.md"))}
    assert "corobot_drake.simulation.Simulation" in named["first_drive.md"]
    assert {f"{p}: {n}" for p in named for n in unreferenced(named[p], page)} == set()


def test_the_name_check_finds_a_name_the_reference_lacks():
    """The check on a page of the test's: names in imports (also parenthesised, renamed) and
    in inline code are found, modules and private names are not; a name is documented under
    its own name or its object's."""
    markdown = ("Run `python -m corobot_drake.ros2.build`; `corobot_drake.resources.scenario_path`"
                "\nnames a file, `corobot_drake.simulation._private` does not count.\n\n"
                "```python\nfrom corobot_drake.simulation import Simulation, Robot as R\n"
                "from corobot_drake.gym.layout import (\n    Layout,\n    draw_layout,\n)\n"
                "import corobot_drake.gym\n```\n")
    names = api_names(markdown)
    assert names == {"corobot_drake.resources.scenario_path",
                     "corobot_drake.simulation.Simulation", "corobot_drake.simulation.Robot",
                     "corobot_drake.gym.layout.Layout", "corobot_drake.gym.layout.draw_layout"}
    page = ('<dt id="corobot_drake.simulation.Simulation"></dt>'
            '<dt id="corobot_drake.gym.layout.Layout"></dt>')
    assert unreferenced(names | {"corobot_drake.gym.env.Layout"}, page) == [
        "corobot_drake.gym.layout.draw_layout", "corobot_drake.resources.scenario_path",
        "corobot_drake.simulation.Robot"]


OWN_TESTS = {"extending": "tests/packaging/test_extending_docs.py",
             "gallery": "tests/packaging/test_refresh_docs.py"}
"""Tutorials whose code another test runs, not test_tutorials.py: extending.md's blocks and
excerpts (held to the files), the gallery's generated pictures (tools/refresh_docs.py; each
shipped scenario's run headless: tests/service/test_cli.py)."""


def tutorials(index: str) -> list[str]:
    """The pages of docs/index.md's "Tutorials" toctree (`index`: its Markdown)."""
    tree = re.search(r"^```\{toctree\}\n:caption: Tutorials\n(.*?)^```", index, re.M | re.S)
    return [line.strip() for line in tree[1].splitlines()
            if line.strip() and not line.startswith(":")]


def test_every_tutorial_is_run_by_a_test():
    """Each page of the site's Tutorials is one test_tutorials.py runs (its `PAGES`), or one
    of `OWN_TESTS`, whose test names the page: a new tutorial cannot go untested silently."""
    from test_tutorials import PAGES

    pages = tutorials((DOCS / "index.md").read_text())
    assert {"install", "first_drive", "extending", "gallery"} <= set(pages)
    assert [p for p in pages if f"docs/{p}.md" not in PAGES and p not in OWN_TESTS] == []
    assert [page for page, test in OWN_TESTS.items() if page not in (REPO / test).read_text()
            ] == []


def github_anchors(markdown: str) -> set[str]:
    """The anchors GitHub (and MyST's `myst_heading_anchors`) gives a page's headings: the
    heading's text lower-cased, punctuation dropped, spaces made hyphens, a repeat suffixed -1,
    -2, ... (headings inside fenced code are not headings)."""
    anchors, seen = set(), {}
    for line in re.sub(r"^(```+|~~~+).*?^\1", "", markdown, flags=re.M | re.S).splitlines():
        heading = re.match(r"#{1,6}\s+(.*?)\s*#*\s*$", line)
        if heading:
            words = re.sub(r"[`*]|\[([^\]]*)\]\([^)]*\)", r"\1", heading[1]).strip().lower()
            slug = re.sub(r"[^\w\- ]", "", words).replace(" ", "-")
            n = seen.get(slug, 0)
            seen[slug] = n + 1
            anchors.add(slug if n == 0 else f"{slug}-{n}")
    return anchors


def broken_links(readme, root) -> list[str]:
    """Each relative link of a Markdown file (Markdown or HTML, outside code) that names no file
    under `root`, or an #anchor that is no heading of the page it points to."""
    source = re.sub(r"^(```+|~~~+).*?^\1|`[^`\n]*`", "", readme.read_text(), flags=re.M | re.S)
    targets = re.findall(r"\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)", source)
    targets += re.findall(r"""\b(?:href|src)=["']([^"']+)["']""", source)
    assert targets, f"no links found in {readme}"
    broken = []
    for target in targets:
        if re.match(r"[a-z][a-z0-9+.-]*:", target):
            continue  # https:, mailto: ...: another site
        path, _, anchor = target.partition("#")
        page = (readme.parent / path).resolve() if path else readme
        if not page.is_file() or root.resolve() not in page.parents:
            broken.append(f"{target}: no such file")
        elif anchor and anchor not in github_anchors(page.read_text()):
            broken.append(f"{target}: no heading #{anchor} in {page.name}")
    return broken


def test_every_relative_link_in_the_readme_resolves():
    """README.md is outside the site's build, so Sphinx does not check it: each relative link
    names a file of the repository, and each #anchor a heading of its page (GitHub's anchors)."""
    assert broken_links(REPO / "README.md", REPO) == []


def test_the_readme_link_check_finds_a_broken_link_and_anchor(tmp_path):
    """The check on a README of the test's: a missing file, a missing anchor and a heading that
    is only inside code are found; GitHub's anchors (punctuation dropped, repeats numbered)."""
    anchors = github_anchors("# Corobot-drake\n## What it does: `x` & y\n## Notes\n## Notes\n"
                             "```\n# not a heading\n```\n")
    assert anchors == {"corobot-drake", "what-it-does-x--y", "notes", "notes-1"}
    (tmp_path / "docs").mkdir()
    (tmp_path / "docs" / "a.md").write_text("# A\n\n## Set up\n\n```\n# Code\n```\n")
    readme = tmp_path / "README.md"
    readme.write_text("# R\n\n[a](docs/a.md#set-up) [b](docs/b.md) [c](docs/a.md#code) "
                      "[d](#r) [e](#nowhere) [f](https://example.org/x.md) `[g](no.md)`\n"
                      '<img src="docs/none.png">\n')
    assert broken_links(readme, tmp_path) == [
        "docs/b.md: no such file", "docs/a.md#code: no heading #code in a.md",
        "#nowhere: no heading #nowhere in README.md", "docs/none.png: no such file"]
