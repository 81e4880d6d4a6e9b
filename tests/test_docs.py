"""The README's and docs' command examples run as written (those that need no hardware and
finish in seconds), from a scratch folder laid out like the repository: its ``examples``
and ``library``, ``.venv/bin`` and ``../shared`` beside it."""

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SHARED = ROOT.parent / "shared"
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
# left out, with why: set-up and suites (make), minutes of work covered by their own tests
SLOW = ("make ", "bench", "laban train", "laban eval", "my-effort.npz", "render ", "record ")


def commands(page: Path) -> list[str]:
    out = []
    for block in re.findall(r"```sh\n(.*?)```", page.read_text(), re.S):
        out += [line for line in block.splitlines() if line.strip() and not line.lstrip().startswith("#")]
    return out


def test_every_page_shows_commands():
    assert all(commands(page) for page in (ROOT / "README.md", ROOT / "docs" / "cli.md"))


@pytest.fixture(scope="module")
def scratch(tmp_path_factory):
    base = tmp_path_factory.mktemp("docs")
    work = base / "repo"
    (work / ".venv" / "bin").mkdir(parents=True)
    for name in ("examples", "library"):
        (work / name).symlink_to(ROOT / name)
    (work / ".venv" / "bin" / "doodle").symlink_to(Path(sys.executable).parent / "doodle")
    (work / ".venv" / "bin" / "python").symlink_to(sys.executable)
    if SHARED.exists():
        (base / "shared").symlink_to(SHARED)
    return work


def runnable(page: Path) -> list[str]:
    """The page's commands that run here: no placeholder, not slow, the data they read
    present (directly, through a variable set to a path in it, or through what a command
    that reads it writes with ``-o``)."""
    import shlex

    out, names, paths = [], set(), set()
    for line in commands(page):
        if "<" in line or any(s in line for s in SLOW):
            continue
        words = shlex.split(line, comments=True)
        needs = "../shared" in line or any(f"${n}" in line for n in names) or any(w in paths for w in words)
        if needs and not SHARED.exists():
            if re.fullmatch(r"[A-Z]+=\S+", line.strip()):
                names.add(line.strip().split("=", 1)[0])
            paths.update(b for a, b in zip(words, words[1:]) if a in ("-o", "--output", "--library"))
            continue
        out.append(line)
    return out


@pytest.mark.parametrize("page", [str(p.relative_to(ROOT)) for p in PAGES if runnable(p)])
def test_commands_run_as_written(page, scratch, monkeypatch):
    """``doodle`` commands run in this process (what the shell would pass them, without a
    second of start-up each); anything else through bash."""
    import shlex

    from doodle.app.cli.main import main

    env = dict(os.environ, PYTHONPATH=str(ROOT))
    monkeypatch.chdir(scratch)
    variables = {}
    for line in runnable(ROOT / page):
        if re.fullmatch(r"[A-Z]+=\S+", line.strip()):
            name, value = line.strip().split("=", 1)
            variables[name] = value
            continue
        if line.startswith(".venv/bin/doodle "):
            for name, value in variables.items():
                line = line.replace(f"${name}", value)
            argv = shlex.split(line, comments=True)[1:]
            ok = (0, 4) if argv[0] == "qa" else (0,)  # qa exits 4 when the animation fails its check
            assert main(argv) in ok, f"{page}: {line}"
            continue
        done = subprocess.run(["bash", "-c", "set -e\n" + line], cwd=scratch, env=env, capture_output=True, text=True,
                              timeout=300)
        assert done.returncode == 0, f"{page}: {line}\n{done.stderr[-2000:]}"


def test_the_readme_quotes_what_make_demo_prints(scratch, monkeypatch, capsys):
    """Every line the README quotes from ``make demo`` is printed by it today."""
    from doodle.app.cli.main import main

    text = (ROOT / "README.md").read_text()
    quoted = re.search(r"What `make demo` prints today.*?```\n(.*?)```", text, re.S).group(1).splitlines()
    monkeypatch.chdir(scratch)
    makefile = (ROOT / "Makefile").read_text()
    demo = re.search(r"^demo:.*?\n((?:\t.*\n)+)", makefile, re.M).group(1).split("\n")
    for line in filter(None, (d.strip() for d in demo)):
        assert main(line.split()[1:]) == 0, line
    printed = capsys.readouterr().out.splitlines()
    for line in quoted:
        if line.strip() != "...":
            assert line in printed, line
