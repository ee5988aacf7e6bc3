"""The tutorials' code runs as written.

Every fenced code block of a tutorial page (and of the README, and of docs/costs.md's Python)
marked as Python (```` ```python ````) or as shell commands (```` ```sh ````) runs here, the
page's blocks in the page's order, in one scratch folder where `scenarios/` is the
repository's, as a reader pastes them one after the other:

- The Python blocks run in one namespace. What a block shows it prints (the `# ...` lines
  right after a top-level `print(` line) it must print, in that order, each line as shown
  (other prints may print more between them); a block a cut below changes is not held to its
  output (its run is shorter).
- Each line of a shell block runs (a trailing backslash joins the next line; `# ...` is a
  comment) and must succeed; a line no rule below runs fails the test, so none is passed over.
  `python` may be written `.venv/bin/python`:
  - `python -m corobot_drake ...` runs in this process through `corobot_drake.cli.main`. A
    command without `--headless` (Meshcat in a browser) gets it, and one without `--duration`
    (until Ctrl-C) gets `--duration 1`: the same run, ended. `--foxglove` without a port gets
    a free one (its 8765 may be taken). A `--serve` command is started as a server (on a free
    port in place of the page's 50000) for the page's Python blocks and `curl` lines, at the
    page's pace (real time), until the last block that names its URL.
  - `python -m corobot_drake.<module> ...` runs that module's (or package's `__main__`'s)
    `main` in this process.
  - `python tools/<tool>.py ...` (or `examples/<example>.py`) runs the script in this
    process, as `python` would; a long measurement is given the small size its flag allows
    (`TOOL_CUTS`). A tool in `SERVING_TOOLS` that starts a server of its own (no `--url`, no
    `--local`) starts it at `--rate max` (`SERVER_RATE`); given the page's server (`--url`),
    it drives a server of its own started as the page's is but at `--rate max`, for that line
    only (a real-time server would take tens of seconds a loop; one at max burns a core while
    it runs). A tool in `VERDICT_TOOLS` may also end with its verdict's exit status 1: its cut
    run decides nothing.
  - `curl ...` runs against the page's server, with `--fail-with-body` (an HTTP error fails).
  - `cat FILE` runs as written: FILE must be there.
- To keep the suite cheap, a run is cut to `MAX_SECONDS` of simulated time: a longer
  `--duration` or `--time`, and a longer literal `advance(S)` in a Python block, are cut to
  it. A study (`python -m corobot_drake.study`, or a tool's) runs only its first run (the
  first grid point, the first seed), on the session's Ray head (conftest's `ray_head`; a
  page that runs one is in `ON_RAY`). In a Python block, a literal `seeds=range(N)` (episodes)
  is cut to `range(1)` and a literal `frames=N` (a measurement's) to `MAX_FRAMES`; a training
  (PPO's) to one short iteration in one worker: `total_timesteps=N` to 1 (Stable-Baselines3
  collects one rollout and updates once) with `n_steps=N` and `batch_size=N` at most
  `MAX_STEPS` and `n_envs=N` (its worker processes) to 1, and `for _ in range(N):` (RLlib's
  iterations) to `range(1)` with `train_batch_size_per_learner=N` at most `MAX_BATCH` and
  `num_env_runners=N` (its actors, on the Ray head) to 0, its sampling in the driver: each
  worker process or actor imports PyTorch and Drake (a remote runner about 10 s). The code
  is otherwise as written: the same calls, the same outputs, a shorter run.
- A block right after a line `<!-- no-test: REASON -->` (the last non-blank line above its
  fence) is not run here; the reason must be said (a display, a dependency the project does
  not have, the set-up or the suite itself; or "run by tests/<tier>/test_x.py, which reads this
  block", a test that does read the page), and the page shows nothing of the comment.

docs/extending.md has its own test (tests/packaging/test_extending_docs.py: its excerpts are
held to the files). docs/gallery.md's commands are the generated pictures' own
(tools/refresh_docs.py) and each shipped scenario's run (tests/service/test_cli.py runs every
one headless). Indented blocks are not code to run: synopses (`[--workers N]`), output, and
the commands of generated blocks.
"""

from __future__ import annotations

import contextlib
import importlib.util
import io
import os
import re
import runpy
import shlex
import socket
import subprocess
import sys
import textwrap

import pytest

from conftest import REPO

PAGES = ("README.md", *(f"docs/{p}.md" for p in (
    "install", "first_drive", "scripting", "usage", "commands", "services", "sensors",
    "recording", "ros2", "studies", "gym", "magellan", "looks", "tuning", "costs")))
ON_RAY = ("docs/commands.md", "docs/studies.md", "docs/gym.md", "docs/tuning.md")
"""The pages whose blocks run studies or rollouts on Ray."""
MAX_SECONDS = 2.0
"""s of simulated time a run here lasts at most."""
MAX_FRAMES = 3
"""Frames a camera measurement renders here at most."""
MAX_STEPS = 16
"""Env steps per env of a Stable-Baselines3 rollout (and of its minibatch) here at most."""
MAX_BATCH = 128
"""Env steps of an RLlib training batch here at most: its PPO's default minibatch, and more than
an episode (60 steps at most), so that one ends: RLlib reports a return only then."""
TOOL_CUTS = {
    "drive_test.py": {"--loops": "1"},                  # 38 s simulated a loop
    "calibrate_odometry.py": {"--side": "0.25", "--loops": "1",   # 1 m squares: 110 s simulated
                              "--out": "calibrate_odometry"},    # not a new folder in /tmp
    "step_limit.py": {"--steps": "0.01"},               # one plant step of eight
    "drive_legs.py": {"--loops": "1"},                 # 38 s simulated a loop
}
"""tool or example -> {flag: value} it runs with here (in place of the page's, or added)."""
PAGE_URL = "http://127.0.0.1:50000"
"""The page's server as the page names it."""
SERVER_RATE = "max"
"""--rate of a server a serving tool drives here (its own, or one in place of the page's): the
same legs, at the machine's pace instead of the wall clock's (in real time a drive_legs loop
takes tens of seconds)."""
SERVING_TOOLS = ("drive_legs.py",)
"""Tools that start a server of their own unless given `--url` (or `--local`), and take its
`--rate`."""
VERDICT_TOOLS = ("tune_tire_grip.py",)
"""Tools whose exit status 1 is their verdict (no effort limit passes), not an error."""
FENCE = re.compile(r"^(?P<indent> *)```(?P<lang>python|sh)\n(?P<body>.*?)^(?P=indent)```$",
                   re.MULTILINE | re.DOTALL)
"""A fenced block, also one indented under a list item."""
NO_TEST = re.compile(r"^<!-- no-test: (?P<reason>\S.*?) -->$")
RUN_BY = re.compile(r"^run by (?P<test>tests/\w+/test_\w+\.py), which reads this block")
PYTHON = ("python", ".venv/bin/python")


def blocks(page: str) -> list[tuple[str, str, int, str | None]]:
    """(language, code, line, no-test reason or None) of each Python or shell block."""
    text = (REPO / page).read_text()
    out = []
    for m in FENCE.finditer(text):
        above = [ln for ln in text[:m.start()].splitlines() if ln.strip()]
        skip = NO_TEST.match(above[-1].strip()) if above else None
        out.append((m["lang"], textwrap.dedent(m["body"]), text.count("\n", 0, m.start()) + 1,
                    skip["reason"] if skip else None))
    return out


def shell_lines(code: str) -> list[list[str]]:
    """The commands of a shell block, as argument lists (comments and blank lines gone)."""
    joined = re.sub(r"\\\n\s*", " ", code)
    return [argv for line in joined.splitlines() if (argv := shlex.split(line, comments=True))]


def cli_commands(code: str) -> list[list[str]]:
    """The `python -m corobot_drake` commands of a shell block, as argument lists."""
    return [argv[3:] for argv in shell_lines(code)
            if argv[0] in PYTHON and argv[1:3] == ["-m", "corobot_drake"]]


def cut(argv: list[str]) -> list[str]:
    """A command as the test runs it: headless, ended, at most MAX_SECONDS long."""
    argv = [*argv, *(["--headless"] if "--headless" not in argv else []),
            *(["--duration", "1"] if "--duration" not in argv else [])]
    at = argv.index("--duration") + 1
    argv[at] = str(min(float(argv[at]), MAX_SECONDS))
    if "--foxglove" in argv:
        at = argv.index("--foxglove") + 1
        if at == len(argv) or not argv[at].isdigit():
            argv.insert(at, str(free_port()))
    return argv


def cut_tool(name: str, args: list[str]) -> list[str]:
    """A tool's arguments as the test runs it: `TOOL_CUTS`' values, `--time` at most
    MAX_SECONDS, `SERVER_RATE` for a server of its own."""
    args = list(args)
    if name in SERVING_TOOLS and not {"--url", "--local", "--rate"} & set(args):
        args += ["--rate", SERVER_RATE]
    for flag, value in TOOL_CUTS.get(name, {}).items():
        if flag in args:
            at = args.index(flag) + 1
            end = next((i for i in range(at, len(args)) if args[i].startswith("-")), len(args))
            args[at:end] = [value]
        else:
            args += [flag, value]
    if "--time" in args:
        at = args.index("--time") + 1
        args[at] = str(min(float(args[at]), MAX_SECONDS))
    return args


def shortened(code: str) -> str:
    """A Python block cut as the module's docstring says: `advance(S)`, `seeds=range(N)`,
    `frames=N`, a training's steps and iterations."""
    code = re.sub(r"\.advance\((\d+(?:\.\d*)?)\)",
                  lambda m: f".advance({min(float(m[1]), MAX_SECONDS)!r})", code)
    code = re.sub(r"\bseeds=range\(\d+\)", "seeds=range(1)", code)
    code = re.sub(r"\bframes=(\d+)\b", lambda m: f"frames={min(int(m[1]), MAX_FRAMES)}", code)
    code = re.sub(r"\btotal_timesteps=[\d_]+", "total_timesteps=1", code)
    code = re.sub(r"\bn_envs=\d+", "n_envs=1", code)
    code = re.sub(r"\bnum_env_runners=\d+", "num_env_runners=0", code)
    code = re.sub(r"^(\s*)for _ in range\([\d_]+\):", r"\1for _ in range(1):", code,
                  flags=re.MULTILINE)
    code = re.sub(r"\b(n_steps|batch_size)=([\d_]+)",
                  lambda m: f"{m[1]}={min(int(m[2]), MAX_STEPS)}", code)
    return re.sub(r"\btrain_batch_size_per_learner=([\d_]+)",
                  lambda m: f"train_batch_size_per_learner={min(int(m[1]), MAX_BATCH)}", code)


def shown_output(code: str) -> list[str]:
    """The lines a Python block shows it prints: the `# ...` comment lines right after each
    top-level `print(` line (up to the next line that is not a comment), trailing spaces gone."""
    shown, after_print = [], False
    for line in code.splitlines():
        if line.startswith("print("):
            after_print = True
        elif after_print and line.startswith("#"):
            shown.append(line[1:].removeprefix(" ").rstrip())
        else:
            after_print = False
    return shown


def run_python(code: str, where: str, namespace: dict) -> None:
    """A Python block run in the page's `namespace` (cut as `shortened` says); an uncut one
    prints what it shows (`shown_output`), in order, among what it prints."""
    run = shortened(code)
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        exec(compile(run, where, "exec"), namespace)
    if run != code:
        return
    printed = iter([line.rstrip() for line in out.getvalue().splitlines()])
    for line in shown_output(code):
        assert line in printed, f"{where}: shows `# {line}`, but it printed:\n{out.getvalue()}"


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture
def scratch(tmp_path, monkeypatch):
    """A folder a reader works in, with the repository's scenarios beside them; a study runs
    its first run only, and never starts a Ray instance of its own."""
    from corobot_drake.study import engine

    (tmp_path / "scenarios").symlink_to(REPO / "scenarios")
    monkeypatch.chdir(tmp_path)
    expand = engine.expand
    monkeypatch.setattr(engine, "expand", lambda study: expand(study)[:1])

    def no_local_ray(workers):
        raise AssertionError("a study or rollout started Ray: put its page in ON_RAY")
    monkeypatch.setattr(engine, "_start_local", no_local_ray)
    return tmp_path


def test_the_tutorials_have_code_and_every_skip_says_why():
    found = {page: blocks(page) for page in PAGES}
    assert sum(len(b) for b in found.values()) >= 25
    for page, page_blocks in found.items():
        for _, _, line, reason in page_blocks:
            assert reason is None or len(reason) > 10, f"{page}:{line}: say why: {reason!r}"
            if reason and (by := RUN_BY.match(reason)):
                assert page in (REPO / by["test"]).read_text(), f"{page}:{line}: {reason}"
    shells = [b for page_blocks in found.values() for b in page_blocks if b[0] == "sh"]
    assert sum(len(cli_commands(code)) for _, code, _, skip in shells if skip is None) >= 5


def test_the_cuts_keep_a_command_and_only_shorten_it():
    assert cut(["--duration", "20", "--mcap", "run.mcap"]) == [
        "--duration", "2.0", "--mcap", "run.mcap", "--headless"]
    assert cut(["--foxglove", "--headless"])[1].isdigit()  # a free port
    assert cut(["--headless", "--foxglove"])[2].isdigit()
    assert cut(["--foxglove", "9000"])[:2] == ["--foxglove", "9000"]
    assert cut_tool("step_limit.py", ["--steps", "0.005", "0.01", "--x"]) == [
        "--steps", "0.01", "--x"]
    assert cut_tool("drive_test.py", ["--seeds", "20"]) == ["--seeds", "20", "--loops", "1"]
    assert cut_tool("snapshot.py", ["--time", "3"]) == ["--time", "2.0"]
    assert cut_tool("drive_legs.py", ["--seed", "1"]) == [
        "--seed", "1", "--rate", "max", "--loops", "1"]
    assert cut_tool("drive_legs.py", ["--url", "U"]) == ["--url", "U", "--loops", "1"]
    assert shortened("sim.advance(5.0); rollouts(p, seeds=range(100)); f(frames=300)") == (
        "sim.advance(2.0); rollouts(p, seeds=range(1)); f(frames=3)")
    assert shortened("v(n_envs=2); PPO(e, n_steps=512, batch_size=8)\n"
                     "m.learn(total_timesteps=200_000)\n"
                     "c.env_runners(num_env_runners=2).training(train_batch_size_per_learner=4_000)\n"
                     "for _ in range(20):\n    a.train()\nfor i in range(20): f(i)") == (
        "v(n_envs=1); PPO(e, n_steps=16, batch_size=8)\nm.learn(total_timesteps=1)\n"
        "c.env_runners(num_env_runners=0).training(train_batch_size_per_learner=128)\n"
        "for _ in range(1):\n    a.train()\nfor i in range(20): f(i)")


def test_a_blocks_shown_output_is_the_comments_right_after_its_prints():
    code = ("x = 1\n# a comment after a line that prints nothing\nprint(x)\n# 1  \n"
            "#second line\ny = x  # not output\n# nor this\nprint(x, y)\n# 1 1\n"
            "    print(y)\n    # indented: not top-level\n")
    assert shown_output(code) == ["1", "second line", "1 1"]


def served(page: str) -> list[str] | None:
    """The arguments of the page's `python -m corobot_drake --serve ...` command, if any."""
    return next((argv for lang, code, _, reason in blocks(page) if lang == "sh" and not reason
                 for argv in cli_commands(code) if "--serve" in argv), None)


def run_line(argv: list[str], where: str, url: str | None, capsys,
             serve: list[str] | None = None) -> None:
    """One shell command of a page, by the rules of the module's docstring (`serve`: the
    arguments of the page's server, `url`)."""
    if argv[0] in PYTHON and argv[1:3] == ["-m", "corobot_drake"]:
        if "--serve" in argv:  # runs until Ctrl-C: served for the page's blocks instead
            return
        run_main("corobot_drake.cli", cut(argv[3:]), where, capsys)
    elif argv[0] in PYTHON and argv[1] == "-m" and argv[2].startswith("corobot_drake."):
        package = importlib.util.find_spec(argv[2]).submodule_search_locations is not None
        run_main(argv[2] + (".__main__" if package else ""), argv[3:], where, capsys)
    elif argv[0] in PYTHON and re.fullmatch(r"(tools|examples)/\w+\.py", argv[1]):
        if "--url" in argv:
            assert url, f"{where}: --url without the page's server (`--serve`)"
            if argv[1].rsplit("/", 1)[1] in SERVING_TOOLS:
                from corobot_drake.serving.serve import ServerProcess

                with ServerProcess([*serve, "--rate", SERVER_RATE]) as fast:
                    argv = [a.replace(PAGE_URL, fast.url) for a in argv]
                    return run_tool(argv[1], argv[2:], where, capsys)
            argv = [a.replace(PAGE_URL, url) for a in argv]
        run_tool(argv[1], argv[2:], where, capsys)
    elif argv[0] == "curl":
        assert url, f"{where}: curl without the page's server (`--serve`)"
        argv = [a.replace(PAGE_URL, url) for a in argv]
        done = subprocess.run([argv[0], "--fail-with-body", *argv[1:]], capture_output=True,
                              text=True, timeout=60)
        assert done.returncode == 0, f"{where}: {shlex.join(argv)}\n{done.stdout}{done.stderr}"
    elif argv[0] == "cat":
        done = subprocess.run(argv, capture_output=True, text=True, timeout=60)
        assert done.returncode == 0 and done.stdout, f"{where}: {shlex.join(argv)}: {done.stderr}"
    else:
        pytest.fail(f"{where}: no rule runs `{shlex.join(argv)}` (tests/packaging/"
                    "test_tutorials.py): give it one, or mark the block no-test with the "
                    "reason (e.g. it needs a ROS 2 install)")


def run_main(module: str, argv: list[str], where: str, capsys) -> None:
    import importlib

    try:
        status = importlib.import_module(module).main(argv)
    except SystemExit as exit_:
        status = exit_.code
    out = capsys.readouterr()
    assert status in (0, None), f"{where}: {module} {shlex.join(argv)}\n{out.err[-2000:]}"


def run_tool(path: str, args: list[str], where: str, capsys) -> None:
    """A script of tools/ or examples/ (`path`) run as `python path args` would."""
    name = path.rsplit("/", 1)[1]
    argv = [str(REPO / path), *cut_tool(name, args)]
    saved = sys.argv
    sys.argv = argv
    try:
        runpy.run_path(argv[0], run_name="__main__")
        status = 0
    except SystemExit as exit_:
        status = exit_.code
    finally:
        sys.argv = saved
    out = capsys.readouterr()
    allowed = (0, None, 1) if name in VERDICT_TOOLS else (0, None)
    assert status in allowed, f"{where}: {shlex.join(argv)} exited {status}\n" \
        f"{out.out[-1000:]}{out.err[-2000:]}"


def run_page(page: str, capsys) -> None:
    """The page's blocks in its order, with its server (if it serves one) on a free port
    until the last block that names the server's URL."""
    from corobot_drake.serving.serve import ServerProcess

    serve = served(page)
    runs = [b for b in blocks(page) if b[3] is None]
    last_use = max((i for i, b in enumerate(runs) if PAGE_URL in b[1]), default=-1)
    with contextlib.ExitStack() as stack:
        url = None
        args = [a for a in serve or () if a != "--serve"]
        if serve:
            url = stack.enter_context(ServerProcess(args)).url
        namespace = {"__name__": "docs_" + re.sub(r"\W", "_", page)}
        for i, (lang, code, line, _) in enumerate(runs):
            if i > last_use:
                stack.close()
                url = None
            if lang == "python":
                if url:
                    code = code.replace(PAGE_URL, url)
                run_python(code, f"{page}:{line}", namespace)
                continue
            for argv in shell_lines(code):
                run_line(argv, f"{page}:{line}", url, capsys, args)


@pytest.mark.parametrize("page", [p for p in PAGES if p not in ON_RAY])
def test_a_pages_blocks_run_in_order(page, scratch, capsys):
    run_page(page, capsys)
    assert os.getcwd() == str(scratch)


@pytest.fixture
def on_ray(ray_head):
    """This process connected to the session's Ray head, and left as it was found."""
    import ray

    ray.init(address=ray_head.address, log_to_driver=False, configure_logging=False)
    yield
    ray.shutdown()


@pytest.mark.parametrize("page", ON_RAY)
def test_a_pages_blocks_run_in_order_on_ray(page, scratch, on_ray, capsys):
    run_page(page, capsys)
    assert os.getcwd() == str(scratch)


YAML_FENCE = re.compile(r"^```yaml\n(?P<body>.*?)^```$", re.MULTILINE | re.DOTALL)


def scenario_blocks(page: str) -> list[tuple[str, int]]:
    """(text, line) of each YAML block of the page that is a scenario (its top-level keys
    are all the Scenario's fields; a study's or a robot file's are not)."""
    import dataclasses as dc

    from corobot_drake.config.scenario import Scenario

    fields = {f.name for f in dc.fields(Scenario)}
    text = (REPO / page).read_text()
    out = []
    for m in YAML_FENCE.finditer(text):
        keys = set(re.findall(r"^(\w+):", m["body"], re.MULTILINE))
        if keys and keys <= fields:
            out.append((m["body"], text.count("\n", 0, m.start()) + 1))
    return out


def test_a_pages_scenario_blocks_load(scratch):
    """A scenario a page shows (usage.md's world and robot, with a maze) loads as written:
    what a reader pastes into a file is a scenario the loader takes."""
    from corobot_drake.config.scenario import load_scenario

    found = {page: scenario_blocks(page) for page in PAGES}
    assert len(found["docs/usage.md"]) >= 2
    for page, page_blocks in found.items():
        for text, line in page_blocks:
            try:
                load_scenario(data=text)
            except Exception as e:
                pytest.fail(f"{page}:{line}: {e}")
