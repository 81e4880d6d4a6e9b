"""``doodle compile`` given several files or a folder: each file compiled on Dask exactly as
it would be alone (byte for byte: BVH files and report.json), a bad file failing alone in
its row of the summary table, inputs and output folders planned before any work, and Dask
never loaded by a single compile."""

import json
import os
import subprocess
import sys
import warnings
from pathlib import Path

import pytest

from doodle.app import batch
from doodle.app.cli.main import main
from doodle.core.errors import DoodleError
from doodle.input.fileformat import write_doodle
from doodle.synth.strokes import stroke, synth_doodle

ROOT = Path(__file__).resolve().parents[1]
ENV = dict(os.environ, PYTHONPATH=str(ROOT), OPENBLAS_NUM_THREADS="1")

DOODLES = {  # small scenes of different lengths and actions
    "walk": [stroke("T_STILL", 0.5), stroke("T_Z", 1.0, 0.15), stroke("T_STILL", 0.5)],
    "side": [stroke("T_STILL", 0.5), stroke("T_X", 0.9, 0.12), stroke("T_STILL", 0.5)],
    "stomp": [stroke("T_STILL", 0.5), stroke("T_Y", 0.3, 0.06), stroke("T_N_Y", 0.25, 0.06), stroke("T_STILL", 0.5)],
}


def _write_doodles(folder: Path) -> list[Path]:
    folder.mkdir(parents=True, exist_ok=True)
    paths = []
    for seed, (name, strokes) in enumerate(DOODLES.items(), 1):
        paths.append(folder / f"{name}.doodle")
        write_doodle(paths[-1], synth_doodle({"c0": strokes}, rate=90, seed=seed))
    return paths


def _files(folder: Path) -> dict:
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir())}


def _cli(*argv) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "doodle.app.cli.main", *map(str, argv)], capture_output=True,
                          text=True, cwd=ROOT, env=ENV, timeout=300)


SINGLES = """
import sys
from doodle.app.cli.main import main
for file, out in zip(sys.argv[1::2], sys.argv[2::2]):
    assert main(["compile", file, "-o", out]) == 0
loaded = sorted(m for m in sys.modules if m.split(".")[0] in ("dask", "distributed"))
assert not loaded, f"a single compile loaded {loaded[:3]}"
"""


@pytest.fixture(scope="module")
def batch_run(tmp_path_factory):
    """Three good doodles and a corrupt one in a folder, plus a missing file, compiled as a
    batch on a real local cluster of two worker processes; then each good file compiled
    alone (in another process) into the very folder the batch wrote it to."""
    tmp = tmp_path_factory.mktemp("batch")
    good = _write_doodles(tmp / "takes")
    (tmp / "takes" / "broken.doodle").write_text("# doodle 1\n# device: vive-controller\n1,2,3\n")
    (tmp / "takes" / "notes.txt").write_text("not a doodle\n")
    out = tmp / "out"
    done = _cli("compile", tmp / "takes", tmp / "gone.doodle", "-o", out, "--workers", "2")
    batch_files = {p.stem: _files(out / p.stem) for p in good}
    single = subprocess.run([sys.executable, "-c", SINGLES, *(str(a) for p in good for a in (p, out / p.stem))],
                            capture_output=True, text=True, cwd=ROOT, env=ENV, timeout=300)
    assert single.returncode == 0, single.stderr
    return tmp, good, done, batch_files, {p.stem: _files(out / p.stem) for p in good}


def test_each_file_is_compiled_as_it_would_be_alone(batch_run):
    tmp, good, done, batch_files, single_files = batch_run
    assert sorted(os.listdir(tmp / "out")) == ["side", "stomp", "walk"]
    for stem in ("side", "stomp", "walk"):
        assert sorted(batch_files[stem]) == ["c0.bvh", "report.json"]
        assert batch_files[stem] == single_files[stem], stem  # byte for byte, report.json's paths too
        report = json.loads(batch_files[stem]["report.json"])
        assert report["file"] == str(tmp / "takes" / f"{stem}.doodle")
        assert report["tracks"]["c0"]["bvh"] == str(tmp / "out" / stem / "c0.bvh")


def test_a_bad_file_fails_alone_in_its_row(batch_run):
    tmp, good, done, _, _ = batch_run
    assert done.returncode == 1, done.stderr
    assert "Traceback" not in done.stderr + done.stdout
    assert done.stderr == ""  # no log lines of Dask's, no progress bar (not a terminal)
    lines = done.stdout.splitlines()
    assert lines[0].split() == ["file", "status", "tracks", "frames", "check", "seconds", "error"]
    rows = {line.split()[0]: line for line in lines[1:-1]}
    assert list(rows) == [str(tmp / "takes" / f"{n}.doodle") for n in ("broken", "side", "stomp", "walk")] + [
        str(tmp / "gone.doodle")]
    for p in good:
        status, tracks, frames, check = rows[str(p)].split()[1:5]
        report = json.loads((tmp / "out" / p.stem / "report.json").read_text())
        assert (status, tracks, frames) == ("ok", "1", str(report["tracks"]["c0"]["frames"]))
        assert check == ("passes" if report["tracks"]["c0"]["check"]["passes"] else "FAILS")
    broken = rows[str(tmp / "takes" / "broken.doodle")].split(None, 6)
    assert broken[1:5] == ["error", "-", "-", "-"] and broken[6].startswith(f"{tmp / 'takes' / 'broken.doodle'}:")
    assert rows[str(tmp / "gone.doodle")].endswith(f"{tmp / 'gone.doodle'}: no such file")
    assert lines[-1] == f"3 of 5 files compiled, each into {tmp / 'out' / 'STEM'}/; 2 failed"
    assert not (tmp / "out" / "broken").exists() and not (tmp / "out" / "gone").exists()


def test_a_running_scheduler_compiles_the_same(batch_run, tmp_path, capsys, monkeypatch):
    """--scheduler ADDRESS: the tasks go to that scheduler's workers (here one in this process);
    the progress bar moves as files finish."""
    from dask.distributed import LocalCluster

    import doodle.app.cli.compile as command

    tmp, good, _, batch_files, _ = batch_run
    moves = []
    monkeypatch.setattr(command, "progress_bar", lambda stage: lambda i, n: moves.append((stage, i, n)))
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None) as cluster:
        code = main(["compile", *map(str, good[:2]), "-o", str(tmp_path), "--scheduler", cluster.scheduler_address])
    out = capsys.readouterr().out
    assert code == 0, out
    assert out.splitlines()[-1] == f"2 of 2 files compiled, each into {tmp_path / 'STEM'}/"
    assert moves == [("files", 0, 2), ("files", 1, 2), ("files", 2, 2)]
    for p in good[:2]:
        assert (tmp_path / p.stem / "c0.bvh").read_bytes() == batch_files[p.stem]["c0.bvh"]


def _loaded(file, out, options):
    return int("doodle.app.pipeline" in sys.modules), 0, ()


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="workers are forked on Linux only")
def test_local_workers_start_with_what_this_process_loaded():
    """On Linux the local workers are forked from the command's process, which imports the
    compile before the cluster starts (import_compile_modules): they do not import it again."""
    from doodle.app.cli.compile import import_compile_modules

    import_compile_modules()
    rows = batch.run([batch.Job("x.doodle", Path("out/x"))], _loaded, None, 1)
    assert (rows[0].status, rows[0].tracks) == ("ok", 1)


def _malloc_setting(file, out, options):
    return int("MALLOC_TRIM_THRESHOLD_" in os.environ), 0, ()


def test_a_local_cluster_leaves_malloc_alone(monkeypatch):
    """Dask's nanny would set MALLOC_TRIM_THRESHOLD_ in this process's environment and its
    workers' (turning glibc's adaptive mmap threshold off: a fifth slower compiles); not here."""
    monkeypatch.delenv("MALLOC_TRIM_THRESHOLD_", raising=False)
    rows = batch.run([batch.Job("x.doodle", Path("out/x"))], _malloc_setting, None, 1)
    assert (rows[0].status, rows[0].tracks) == ("ok", 0)
    assert "MALLOC_TRIM_THRESHOLD_" not in os.environ


# --- planned before any work ----------------------------------------------------------------

def test_a_folder_means_its_doodle_and_csv_files(tmp_path):
    for name in ("b.doodle", "A.CSV", "c.csv", "notes.txt", "d.doodle.bak"):
        (tmp_path / name).write_text("")
    (tmp_path / "sub.doodle").mkdir()
    assert batch.expand_inputs([str(tmp_path), "x.doodle"]) == [str(tmp_path / n) for n in ("A.CSV", "b.doodle",
                                                                                             "c.csv")] + ["x.doodle"]
    from doodle.app.cli.compile import is_batch

    assert is_batch([str(tmp_path)]) and is_batch(["a", "b"]) and not is_batch(["a.doodle"])


def test_a_folder_without_doodles_is_refused(tmp_path, capsys):
    code = main(["compile", str(tmp_path), "-o", str(tmp_path / "out")])
    assert code == 1
    assert capsys.readouterr().err == (f"doodle: error: {tmp_path}: no doodle files in this folder "
                                       "(looked for .doodle, .csv)\n")


def test_two_inputs_of_one_stem_are_refused_naming_both(tmp_path, capsys):
    a, b = tmp_path / "x" / "take.doodle", tmp_path / "y" / "Take.csv"
    code = main(["compile", str(a), str(b), "-o", str(tmp_path / "out")])
    assert code == 1
    assert capsys.readouterr().err == (f"doodle: error: {a} and {b} would both be compiled into "
                                       f"{tmp_path / 'out' / 'Take'}; rename one, or compile them into different "
                                       "folders\n")
    with pytest.raises(DoodleError, match="given twice"):
        batch.plan(["a.doodle", "a.doodle"], Path("out"))
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("argv, said", [
    (["--workers", "0"], "--workers must be 1 or more, not 0"),
    (["--workers", "2", "--scheduler", "tcp://h:1"], "compile: give --workers N or --scheduler ADDRESS, not both"),
    (["--time", "2"], "--time must be between -1 and 1, not 2"),
    (["--effort-model", "nowhere.npz"], "nowhere.npz: no such model file"),
    (["--effort-model", "junk.npz"], "junk.npz: not a valid .npz archive (not a zip archive)"),
])
def test_options_every_file_would_fail_on_are_refused_once(argv, said, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    Path("junk.npz").write_text("junk")
    code = main(["compile", "a.doodle", "b.doodle", "-o", str(tmp_path / "out"), *argv])
    assert (code, capsys.readouterr().err) == (1, f"doodle: error: {said}\n")


# --- one job; the table ---------------------------------------------------------------------

def test_a_job_never_raises():
    def bad_input(file, out, options):
        raise DoodleError(f"{file}:3: not a number\n(line two)")

    def bug(file, out, options):
        raise KeyError("x")

    def ok(file, out, options):
        warnings.warn(f"{file}: last row is incomplete")
        warnings.warn(f"{file}: last row is incomplete")
        return 2, 90, ("c1",)

    job = batch.Job("a.doodle", Path("out/a"))
    assert batch.run_job(bad_input, job, None).error == "a.doodle:3: not a number (line two)"
    assert batch.run_job(bug, job, None).error == "internal error: KeyError: 'x'"
    row = batch.run_job(ok, job, None)
    assert (row.status, row.tracks, row.frames, row.warnings, row.failing) == (
        "ok", 2, 90, ("a.doodle: last row is incomplete",), ("c1",))


def test_the_table():
    rows = [batch.Row("takes/walk.doodle", "ok", 1, 61, 1.234),
            batch.Row("takes/pair.doodle", "ok", 2, 300, 2.5, failing=("c1",)),
            batch.Row("gone.doodle", "error", seconds=0.01, error="gone.doodle: no such file")]
    assert batch.table(rows) == [
        "file               status  tracks  frames  check     seconds  error",
        "takes/walk.doodle  ok           1      61  passes        1.2",
        "takes/pair.doodle  ok           2     300  FAILS c1      2.5",
        "gone.doodle        error        -       -  -             0.0  gone.doodle: no such file",
    ]
    assert batch.summary(rows, "out") == ("2 of 3 files compiled, each into out/STEM/; 1 failed; 1 fails the "
                                          "animation check (`doodle qa out/STEM -v` lists the frames)")
    assert batch.summary(rows[:1], "out") == "1 of 1 file compiled, each into out/STEM/"


def test_a_batch_job_computes_with_one_blas_thread():
    """Each worker's BLAS on one thread, whatever it started with: OpenBLAS's own thread per
    core in each of two workers on two cores took a batch of 16 demo copies from 1.4 s to
    2.2-2.3 s (the environment's thread count acts only before numpy is imported, and the
    workers are forked after)."""
    from threadpoolctl import threadpool_info, threadpool_limits

    from doodle.app import batch

    def blas_threads(file, out, options):
        return max(lib["num_threads"] for lib in threadpool_info() if lib["user_api"] == "blas"), 0, ()

    with threadpool_limits(limits=2, user_api="blas"):
        batch._PINNED.clear()  # as a fresh worker
        row = batch.run_job(blas_threads, batch.Job("x.doodle", Path("out")), None)
    assert row.status == "ok" and row.tracks == 1
