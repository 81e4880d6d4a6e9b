"""What the commands write, through the command line: a failed run leaves what was on disk
byte for byte, output paths that cannot be what they should are refused in one line, a file
the user named is replaced only with --overwrite, names never become paths elsewhere, a
library cannot make doodle read outside its folder, and a killed run leaves old or new
outputs, never half of one."""

import json
import os
import random
import shutil
import signal
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
import pytest

from doodle.app.cli.main import main
from doodle.input.fileformat import write_doodle
from doodle.synth.strokes import stroke, synth_doodle

ROOT = Path(__file__).resolve().parents[1]
CLIPS = ROOT / "library" / "builtin" / "clips"


def run(*args, **kw):
    return subprocess.run([sys.executable, "-m", "doodle.app.cli.main", *map(str, args)], capture_output=True, text=True,
                          cwd=ROOT, timeout=120, **kw)


def one_error(code: int, err: str) -> str:
    """The one line a failed command prints, after checking there is only it."""
    lines = err.strip().splitlines()
    assert code == 1, err
    assert "Traceback" not in err and len(lines) == 1 and lines[0].startswith("doodle: error: "), err
    return lines[0]


def fails(capsys, *argv) -> str:
    code = main([str(a) for a in argv])
    return one_error(code, capsys.readouterr().err)


def tree(root: Path) -> dict:
    """Every file (bytes, or the target of a link) and folder under ``root``."""
    out = {}
    for folder, dirs, files in os.walk(root):
        for name in dirs + files:
            path = Path(folder) / name
            rel = str(path.relative_to(root))
            out[rel] = ("link", os.readlink(path)) if path.is_symlink() else (
                "dir" if path.is_dir() else path.read_bytes())
    return out


@pytest.fixture
def clip_folder(tmp_path):
    src = tmp_path / "src"
    src.mkdir()
    for name in ("walk", "jump"):
        shutil.copy(CLIPS / f"{name}.bvh", src)
    return src


def _examples(folder: Path) -> list[Path]:
    paths = []
    for seed in (1, 2, 3):
        d = synth_doodle({"c0": [stroke("T_STILL", 0.4), stroke("T_Z", 0.5), stroke("T_Y", 0.4), stroke("T_N_Z", 0.5),
                                 stroke("T_STILL", 0.4)]}, rate=90, seed=seed)
        paths.append(folder / f"ex{seed}.doodle")
        write_doodle(paths[-1], d)
    return paths


@pytest.fixture
def examples(tmp_path):
    folder = tmp_path / "examples"
    folder.mkdir()
    return _examples(folder)


def _walk_doodle(path: Path) -> Path:
    write_doodle(path, synth_doodle({"c0": [stroke("T_STILL", 0.5), stroke("T_Z", 1.0, 0.15), stroke("T_STILL", 0.5)]},
                                    seed=1))
    return path


@pytest.fixture
def walk(tmp_path):
    return _walk_doodle(tmp_path / "walk.doodle")


# --- a failed run changes nothing ---------------------------------------------------------

def test_a_failed_import_leaves_the_library_as_it_was(tmp_path, clip_folder):
    lib = tmp_path / "lib"
    assert main(["library", "import", str(clip_folder), "--name", "t", "-o", str(lib)]) == 0
    assert sorted(p.name for p in (lib / "clips").iterdir()) == ["jump.bvh", "walk.bvh"]  # copied: self-contained
    (lib / "takes").mkdir()
    (lib / "takes" / "mine_1.doodle").write_text("a take of mine\n")
    before, around = tree(lib), sorted(os.listdir(tmp_path))
    (clip_folder / "kick.bvh").write_bytes((CLIPS / "kick.bvh").read_bytes()[:3000])  # truncated
    done = run("library", "import", clip_folder, "--name", "t", "-o", lib)
    line = one_error(done.returncode, done.stderr)
    assert f"{clip_folder / 'kick.bvh'}:" in line  # the file as the user knows it
    assert tree(lib) == before and sorted(os.listdir(tmp_path)) == around
    (clip_folder / "kick.bvh").unlink()
    shutil.copy(CLIPS / "punch.bvh", clip_folder)
    assert main(["library", "import", str(clip_folder), "--name", "t2", "-o", str(lib)]) == 0
    assert sorted(p.name for p in (lib / "clips").iterdir()) == ["jump.bvh", "punch.bvh", "walk.bvh"]
    assert 'name = "t2"' in (lib / "library.toml").read_text()
    assert (lib / "takes" / "mine_1.doodle").read_text() == "a take of mine\n"  # not the import's: kept
    assert sorted(os.listdir(tmp_path)) == around  # no staging folder left


def test_a_failed_learn_leaves_the_library_as_it_was(tmp_path, examples, capsys):
    lib = tmp_path / "lib"
    assert main(["learn", "Hop", *map(str, examples), "--library", str(lib)]) == 0
    capsys.readouterr()
    with open(lib / "library.toml", "a") as fh:  # the user's own action: sets a state nothing clears
        fh.write('\n[[actions]]\nname = "Fall"\nexpression = "T_N_Y"\nsets = ["fallen"]\n')
    before, around = tree(lib), sorted(os.listdir(tmp_path))
    line = fails(capsys, "learn", "Hop", *examples, "--library", lib, "--replace")  # fails once all is written
    assert "'Fall' sets state 'fallen' but no action clears it" in line
    assert "'Fall' sets state 'fallen'" in fails(capsys, "learn", "Skip", *examples, "--library", lib)
    assert tree(lib) == before and sorted(os.listdir(tmp_path)) == around


def test_learn_swaps_the_library_in_without_renameat2(tmp_path, examples, capsys, monkeypatch):
    """Where the system cannot exchange two folders in one step, two renames do."""
    import doodle.core.files

    monkeypatch.setattr(doodle.core.files, "_exchange", lambda a, b: False)
    lib = tmp_path / "lib"
    assert main(["learn", "Hop", *map(str, examples), "--library", str(lib)]) == 0
    assert main(["learn", "Skip", *map(str, examples), "--library", str(lib), "--no-builtin"]) == 0
    from library.manifest import load_library

    assert load_library(lib).names == ["Hop", "Skip"]
    assert sorted(p.name for p in (lib / "shapes").iterdir()) == ["Hop.npz", "Skip.npz"]
    assert sorted(os.listdir(tmp_path)) == ["examples", "lib"]
    capsys.readouterr()


# --- output paths -------------------------------------------------------------------------

def _commands(tmp, walk, examples, clips, blocker):
    """Each command writing an output, its output put at ``blocker`` (a path whose folder
    part is a file)."""
    clip = CLIPS / "punch.bvh"
    return {
        "compile": ["compile", walk, "-o", blocker],
        "compile-sub": ["compile", walk, "-o", blocker / "sub"],
        "library import": ["library", "import", clips, "--name", "t", "-o", blocker],
        "learn": ["learn", "X", *examples, "--library", blocker],
        "laban eval": ["laban", "eval", "-o", blocker],
        "import": ["import", walk, "-o", blocker / "x.doodle"],
        "stylize": ["stylize", clip, "--time", "1", "-o", blocker / "x.bvh"],
        "stylize --compare": ["stylize", clip, "--time", "1", "-o", tmp / "ok.bvh", "--compare", blocker / "x.png"],
        "calibrate": ["calibrate", "--forward", walk, "-o", blocker / "cal.toml"],
        "library sheet": ["library", "sheet", "-o", blocker / "sheet.png"],
        "render": ["render", walk, "-o", blocker / "x.png"],
        "record": ["record", "--source", "synthetic", "--seconds", "0.5", "-o", blocker / "x.doodle"],
        "laban train": ["laban", "train", "--synthetic", "-o", blocker / "m.npz"],
        "laban record": ["laban", "record", "--drive", "Punch", "-o", blocker / "x.doodle"],
    }


@pytest.mark.parametrize("command", ["compile", "compile-sub", "library import", "learn", "laban eval", "import",
                                     "stylize", "stylize --compare", "calibrate", "library sheet", "render", "record",
                                     "laban train", "laban record"])
def test_an_output_under_a_file_is_refused_in_one_line(command, tmp_path, walk, examples, clip_folder, capsys):
    blocker = tmp_path / "out" / "x"
    blocker.parent.mkdir()
    blocker.write_text("mine\n")
    before = tree(tmp_path)
    line = fails(capsys, *_commands(tmp_path, walk, examples, clip_folder, blocker)[command])
    said = f"doodle: error: {blocker}: is a file, expected a folder"
    if command in ("compile", "library import", "learn", "laban eval"):
        assert line == said
    else:  # a file to be written inside it
        assert line.startswith(f"{said} (to hold {blocker}/")
    assert tree(tmp_path) == before


def test_a_folder_where_a_file_is_expected(tmp_path, walk, capsys):
    (tmp_path / "out").mkdir()
    assert fails(capsys, "import", walk, "-o", tmp_path / "out") == f"doodle: error: {tmp_path / 'out'}: is a folder, " \
                                                                    "expected a file"


@pytest.mark.parametrize("command", ["import", "stylize", "stylize --compare", "calibrate", "library sheet", "render",
                                     "record", "laban train", "laban record"])
def test_a_file_the_user_named_is_replaced_only_with_overwrite(command, tmp_path, walk, examples, clip_folder, capsys):
    out = tmp_path / "out"
    out.mkdir()
    argv = [str(a) for a in _commands(tmp_path, walk, examples, clip_folder, out)[command]]
    target = Path(argv[-1])
    target.write_text("mine\n")
    before = tree(tmp_path)
    line = fails(capsys, *argv)
    assert line == f"doodle: error: {target}: already exists (pass --overwrite to replace it)"
    assert tree(tmp_path) == before


def test_import_overwrites_when_asked(tmp_path, walk, capsys):
    out = tmp_path / "take.doodle"
    out.write_text("mine\n")
    assert main(["import", str(walk), "-o", str(out), "--overwrite"]) == 0
    assert out.read_text().startswith("# doodle 1")
    capsys.readouterr()


def test_compile_rewrites_its_own_files_and_leaves_others(tmp_path, walk, capsys):
    out = tmp_path / "out"
    out.mkdir()
    (out / "notes.txt").write_text("mine\n")
    for _ in range(2):  # `make demo` twice
        assert main(["compile", str(walk), "-o", str(out), "--no-effort"]) == 0
    assert sorted(os.listdir(out)) == ["c0.bvh", "notes.txt", "report.json"]
    assert (out / "notes.txt").read_text() == "mine\n"
    capsys.readouterr()


# --- edits naming what is not there -------------------------------------------------------

@pytest.mark.parametrize("entry, said", [
    ({"track": "c7", "time": 1.0}, "segments entry for track 'c7': no such track (tracks: c0)"),
    ({"track": "c0", "index": 3, "time": 1.0}, "segments entry for track 'c0', index 3: track c0 has segments 0–2"),
])
def test_edits_naming_a_missing_track_or_segment(entry, said, tmp_path, walk, capsys):
    edits = tmp_path / "edits.json"
    edits.write_text(json.dumps({"segments": [{"track": "c0", "index": 1, "weight": 0.5}, entry]}))
    before = tree(tmp_path)
    line = fails(capsys, "compile", walk, "-o", tmp_path / "out", "--edits", edits, "--no-effort")
    assert line.startswith(f"doodle: error: {edits}: {said}")
    assert tree(tmp_path) == before


# --- names and paths ----------------------------------------------------------------------

@pytest.mark.parametrize("name", ["../../escaped", "a/b", "..", "/abs/x", "..\\..\\win", ".hidden", "Wave Hello"])
def test_action_names_never_become_paths_elsewhere(name, tmp_path, examples, capsys):
    work = tmp_path / "a" / "b"
    work.mkdir(parents=True)
    before = tree(tmp_path)
    assert main(["learn", name, *map(str, examples), "--library", str(work / "lib")]) == 0
    capsys.readouterr()
    after = tree(tmp_path)
    new = sorted(set(after) - set(before))
    assert all(p.startswith(str(Path("a/b/lib"))) for p in new), new
    assert {k: v for k, v in after.items() if k in before} == before
    shapes = list((work / "lib" / "shapes").iterdir())
    assert len(shapes) == 1 and shapes[0].suffix == ".npz" and not shapes[0].name.startswith(".")
    from library.manifest import load_library

    assert load_library(work / "lib").action(name.strip()).shape == str(shapes[0].resolve())


@pytest.mark.parametrize("name, said", [("a\x00b", "control characters"), ("a\nb", "control characters"),
                                        ("x" * 300, "too long (300 characters; at most 100)"), ("  ", "not usable")])
def test_unusable_action_names_are_refused(name, said, tmp_path, examples, capsys):
    before = tree(tmp_path)
    assert said in fails(capsys, "learn", name, *examples, "--library", tmp_path / "lib")
    assert tree(tmp_path) == before


def test_import_name_as_a_folder_must_be_a_plain_name(tmp_path, clip_folder, capsys, monkeypatch):
    work = tmp_path / "a"
    work.mkdir()
    monkeypatch.chdir(work)  # without -o the library is ./NAME
    before = tree(tmp_path)
    assert "--name '../escaped': not usable as a folder name" in fails(capsys, "library", "import", clip_folder,
                                                                        "--name", "../escaped")
    assert tree(tmp_path) == before


HOSTILE = [
    ('clips = ["../outside.bvh"]', "field 'clips': '../outside.bvh' leads out of the folder"),
    ('clips = ["clips/../../outside.bvh"]', "leads out of the folder"),
    ('clips = ["{outside}"]', "is an absolute path"),
    ('clips = ["clips\\\\..\\\\..\\\\outside.bvh"]', "use / between folders"),
    ('clips = ["clips/a\\u0000.bvh"]', "not a usable path"),
    ('clips = ["clips/' + "x" * 300 + '.bvh"]', "too long"),
    ('clips = ["clips/link.bvh"]', "'clips/link.bvh' leads out of the folder"),  # a link inside, to outside
    ('shape = "../outside.npz"', "field 'shape': '../outside.npz' leads out of the folder"),
    ('\n[[interactions]]\nname = "Two"\nactions = ["Wave", "Wave"]\npair = ["../outside.bvh", "clips/b.bvh"]',
     "interaction 'Two': field 'pair': '../outside.bvh' leads out of the folder"),
]


@pytest.mark.parametrize("field, said", HOSTILE)
@pytest.mark.parametrize("command", ["library list", "learn"])
def test_a_library_cannot_name_files_outside_its_folder(field, said, command, tmp_path, examples, capsys):
    lib = tmp_path / "lib"
    (lib / "clips").mkdir(parents=True)
    shutil.copy(CLIPS / "walk.bvh", tmp_path / "outside.bvh")
    np.savez(tmp_path / "outside.npz", paths=np.zeros((1, 4, 3)))
    os.symlink(tmp_path / "outside.bvh", lib / "clips" / "link.bvh")
    (lib / "library.toml").write_text('[library]\nname = "evil"\nformat = 1\n\n[[actions]]\nname = "Wave"\n'
                                      'expression = "T_X T_N_X"\n' + field.replace("{outside}", str(tmp_path / "outside.bvh"))
                                      + "\n")
    before = tree(tmp_path)
    argv = (["library", "list", "--library", lib] if command == "library list" else
            ["learn", "Hop", *examples, "--library", lib])
    line = fails(capsys, *argv)
    assert line.startswith(f"doodle: error: {lib / 'library.toml'}: ") and said in line, line
    if "interaction" not in said:
        assert "action 'Wave'" in line
    assert tree(tmp_path) == before


def test_qa_reads_the_bvh_files_beside_the_report_only(tmp_path, capsys):
    out = tmp_path / "out"
    out.mkdir()
    shutil.copy(CLIPS / "walk.bvh", out / "c0.bvh")
    shutil.copy(CLIPS / "walk.bvh", tmp_path / "outside.bvh")
    (out / "report.json").write_text(json.dumps({"tracks": {"c0": {"bvh": str(tmp_path / "outside.bvh")}}}))
    line = fails(capsys, "qa", out)  # the report names outside.bvh: looked for beside it, not outside
    assert line.startswith(f"doodle: error: {out / 'outside.bvh'}"), line
    (out / "report.json").write_text(json.dumps({"tracks": {"c0": {"bvh": str(out / "c0.bvh")}}}))
    assert main(["qa", str(out)]) in (0, 4)
    capsys.readouterr()


def test_import_and_learn_only_replace_a_library_or_a_new_folder(tmp_path, clip_folder, examples, capsys):
    home = tmp_path / "home"
    home.mkdir()
    (home / "thesis.tex").write_text("years of work\n")
    before = tree(tmp_path)
    assert "is a folder but not a library" in fails(capsys, "library", "import", clip_folder, "--name", "t", "-o", home)
    assert "is a folder but not a library" in fails(capsys, "learn", "Hop", *examples, "--library", home)
    assert tree(tmp_path) == before


# --- killed runs ----------------------------------------------------------------------------

def _visible(root: Path) -> dict:
    """The files a user looks at: everything under ``root`` but dot-files and dot-folders."""
    return {k: v for k, v in tree(root).items() if not any(part.startswith(".") for part in Path(k).parts)}


def _same_library(before: dict, after: dict) -> None:
    """Old or new complete version of a learned library: manifest as it was (learning is
    deterministic), each shape file whole (same arrays; an .npz carries its write time)."""
    assert after.keys() == before.keys()
    for k in before:
        if k.endswith(".npz"):
            import io

            with np.load(io.BytesIO(before[k])) as a, np.load(io.BytesIO(after[k])) as b:
                assert a.files == b.files and all(np.array_equal(a[f], b[f]) for f in a.files), k
        else:
            assert after[k] == before[k], k


def _equal(before: dict, after: dict) -> None:
    assert after == before  # the command is deterministic: the new version is the old one


def _kill_runs(argv, watched: Path, same, seed: int, kills: int = 2) -> int:
    """Run ``argv`` once to the end, then ``kills`` times killed (SIGKILL) after a seeded
    random share of that run's duration; after each, ``watched`` must hold the complete
    outputs. Returns how many runs were killed before they ended."""
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    cmd = [sys.executable, "-m", "doodle.app.cli.main", *map(str, argv)]
    start = time.perf_counter()
    done = subprocess.run(cmd, capture_output=True, text=True, env=env, cwd=ROOT, timeout=120)
    took = time.perf_counter() - start
    assert done.returncode == 0, done.stderr
    before, around = _visible(watched), {p for p in os.listdir(watched.parent) if not p.startswith(".")}
    rng = random.Random(seed)
    killed = 0
    for _ in range(kills):
        start = time.perf_counter()
        proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env, cwd=ROOT)
        try:
            proc.wait(timeout=rng.uniform(0.3, 0.9) * took)
        except subprocess.TimeoutExpired:
            proc.send_signal(signal.SIGKILL)
            killed += 1
        else:  # it ran faster than the first time (warm caches): aim earlier next time
            took = time.perf_counter() - start
        proc.wait(timeout=60)
        same(before, _visible(watched))
        assert {p for p in os.listdir(watched.parent) if not p.startswith(".")} == around
    return killed


def test_killed_runs_leave_old_or_new_outputs_never_half(tmp_path):
    """`library import`, `learn` and `compile` killed at seeded random moments (three at a
    time, as two cores allow): every output a user looks at is the old or the new version
    whole; leftovers, if any, are dot-files."""
    clips = tmp_path / "src"
    clips.mkdir()
    for name in ("walk", "jump", "kick", "punch"):
        shutil.copy(CLIPS / f"{name}.bvh", clips)
    (tmp_path / "ex").mkdir()
    examples = _examples(tmp_path / "ex")
    walk = _walk_doodle(tmp_path / "walk.doodle")
    for name in ("imported", "learned", "compiled"):
        (tmp_path / name).mkdir()
    jobs = [
        (["library", "import", clips, "--name", "t", "-o", tmp_path / "imported" / "lib"], tmp_path / "imported" / "lib",
         _equal, 1),
        (["learn", "Hop", *examples, "--library", tmp_path / "learned" / "lib", "--replace"],
         tmp_path / "learned" / "lib", _same_library, 2),
        (["compile", walk, "-o", tmp_path / "compiled" / "out", "--no-effort"], tmp_path / "compiled" / "out",
         _equal, 3),
    ]
    with ThreadPoolExecutor(len(jobs)) as pool:
        killed = list(pool.map(lambda job: _kill_runs(*job), jobs))
    assert sum(killed) >= 1  # the kills did land while runs were under way
