"""The `doodle` command line: output formats, and one clear line for bad input."""

import json
import subprocess
import sys
from pathlib import Path

import pytest

from doodle.app.cli.main import main
from doodle.input.fileformat import write_doodle
from doodle.synth.strokes import stroke, synth_doodle

ROOT = Path(__file__).resolve().parents[1]
DEMO = ROOT / "examples" / "demo.doodle"


def run(*args):
    return subprocess.run([sys.executable, "-m", "doodle.app.cli.main", *map(str, args)], capture_output=True, text=True,
                          cwd=ROOT, timeout=120)


@pytest.fixture
def two_tracks(tmp_path):
    doodle = synth_doodle({"c0": [stroke("T_STILL", 0.4), stroke("T_Z", 0.6), stroke("T_STILL", 0.4)],
                           "c1": [stroke("T_STILL", 0.4), stroke("R_Y", 0.6), stroke("T_STILL", 0.4)]}, seed=1)
    path = tmp_path / "two.doodle"
    write_doodle(path, doodle, convention="openvr")
    return path


def test_tokens_json_one_object_per_file(two_tracks, capsys):
    assert main(["tokens", "--json", str(two_tracks), str(DEMO)]) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    assert len(lines) == 2
    first = json.loads(lines[0])
    assert first["file"] == str(two_tracks)
    assert [k["token"] for k in first["tracks"]["c0"]] == ["T_STILL", "T_Z", "T_STILL"]
    assert [k["token"] for k in first["tracks"]["c1"]] == ["T_STILL", "R_Y", "T_STILL"]
    c0 = first["tracks"]["c0"]
    assert c0[0]["start"] == 0.0 and all(a["end"] == b["start"] for a, b in zip(c0, c0[1:]))
    assert c0[-1]["end"] == pytest.approx(1.4, abs=0.1)


def test_tokens_track_selection(two_tracks, capsys):
    assert main(["tokens", "--json", "--tracks", "c1", str(two_tracks)]) == 0
    assert list(json.loads(capsys.readouterr().out)["tracks"]) == ["c1"]


def test_demo_reads_as_the_main_example(capsys):
    assert main(["tokens", str(DEMO)]) == 0
    out = capsys.readouterr().out
    assert "c0: T_STILL T_X T_STILL T_Z T_STILL T_Y T_Y_Z T_N_Y_Z T_N_Y T_STILL T_Z T_STILL T_Y T_N_Y T_STILL" in out


def test_csv_needs_a_convention_and_reads_the_vive_layout(vive_files, capsys):
    assert main(["tokens", str(vive_files[0])]) == 1
    assert "pass --convention" in capsys.readouterr().err
    assert main(["tokens", "--json", "--convention", "unity", str(vive_files[0])]) == 0
    assert set(json.loads(capsys.readouterr().out)["tracks"]) == {"c0", "c1"}


def test_import_then_tokens_agree(vive_files, tmp_path, capsys):
    out = tmp_path / "take.doodle"
    assert main(["import", str(vive_files[0]), "--convention", "unity", "-o", str(out)]) == 0
    capsys.readouterr()
    main(["tokens", "--json", "--convention", "unity", str(vive_files[0])])
    from_csv = json.loads(capsys.readouterr().out)["tracks"]
    main(["tokens", "--json", str(out)])
    from_doodle = json.loads(capsys.readouterr().out)["tracks"]
    assert [k["token"] for k in from_csv["c0"]] == [k["token"] for k in from_doodle["c0"]]


@pytest.mark.parametrize("content, message", [
    ("# doodle 7\n", "version"),
    ("# doodle 1\n# device x\n# rate 90\n# units m\n# convention doodle\n# track c0\n"
     "t,c0.ok,c0.px,c0.py,c0.pz,c0.qx,c0.qy,c0.qz,c0.qw\n0,1,0,0,0,0,0,0,1\n0.01,1,nan,0,0,0,0,0,1\n", ":9"),
    ("# doodle 1\n# device x\n# rate 90\n# units m\n# convention doodle\n# track c0\n"
     "t,c0.ok,c0.px,c0.py,c0.pz,c0.qx,c0.qy,c0.qz,c0.qw\n0,1,0,0,0,0,0,0,1\n0,1,0,0,0,0,0,0,1\n", ":9"),
    ("# doodle 1\n# device x\n# rate 90\n# units m\n# convention doodle\n# track c0\n"
     "t,c0.ok,c0.px,c0.py,c0.pz,c0.qx,c0.qy,c0.qz,c0.qw\n0,1,0,0,0,0,0,0,1\n", "at least two"),
])
def test_bad_files_give_one_line_and_exit_nonzero(tmp_path, content, message):
    path = tmp_path / "bad.doodle"
    path.write_text(content)
    result = run("tokens", path)
    assert result.returncode == 1
    assert "Traceback" not in result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("doodle: error: ") and "bad.doodle" in lines[0]
    assert message in lines[0]


def test_missing_column_in_csv(tmp_path):
    path = tmp_path / "cols.csv"
    path.write_text("t,c0_px,c0_py,c0_pz,c0_qx,c0_qy,c0_qz\n0,0,0,0,0,0,0\n")
    result = run("tokens", "--convention", "unity", path)
    assert result.returncode == 1 and "c0_qw" in result.stderr and "Traceback" not in result.stderr


def test_missing_file_and_good_file_together(two_tracks, tmp_path):
    result = run("tokens", tmp_path / "nope.doodle", two_tracks)
    assert result.returncode == 1
    assert "nope.doodle: no such file" in result.stderr
    assert "T_Z" in result.stdout  # the good file was still processed


def test_truncated_recording_warns_and_loads(two_tracks, tmp_path):
    text = two_tracks.read_text()
    cut = tmp_path / "cut.doodle"
    cut.write_text(text[: len(text) - 25])  # a crash mid-row
    result = run("tokens", cut)
    assert result.returncode == 0
    assert "doodle: warning:" in result.stderr and "incomplete" in result.stderr


def test_calibrate_writes_a_file_tokens_reads(tmp_path, capsys):
    forward = tmp_path / "forward.doodle"
    write_doodle(forward, synth_doodle([stroke("T_STILL", 0.6), stroke("T_Z", 0.5), stroke("T_STILL", 0.3)], seed=2))
    cal = tmp_path / "cal.toml"
    assert main(["calibrate", "--forward", str(forward), "-o", str(cal)]) == 0
    assert "mount c0" in capsys.readouterr().out
    assert main(["tokens", "--calibration", str(cal), str(forward)]) == 0
    assert "T_Z" in capsys.readouterr().out
    assert main(["calibrate", "-o", str(cal)]) == 1


def _help(parser, argv) -> tuple[int, str]:
    """What ``parser`` prints (stdout and stderr) and its exit status for ``argv``."""
    import contextlib
    import io

    out = io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(out):
        try:
            parser.parse_args(argv)
            status = 0
        except SystemExit as e:
            status = e.code
    return status, out.getvalue()


def test_the_parser_built_for_one_command_says_what_the_whole_one_does():
    """``doodle`` builds only the named command's arguments (the others by name and help
    line): every help text and usage error is the same as the whole parser's."""
    from doodle.app.cli.main import COMMANDS, build_parser, named_command

    whole = build_parser()
    cases = [[], ["--help"], ["nosuch"], ["-1", "compile"], ["--", "compile"], ["compile", "x", "--bogus"],
             ["library"], ["laban", "eval", "--help"], ["library", "show", "--help"]]
    cases += [[name, "--help"] for name, *_ in COMMANDS] + [[name] for name, *_ in COMMANDS]
    for argv in cases:
        assert _help(build_parser(named_command(argv)), argv) == _help(whole, argv), argv
    assert named_command(["--help"]) == named_command(["nosuch"]) == []
    assert named_command(["-1", "compile", "x"]) == ["compile"]


def test_doodle_computes_with_one_blas_thread_unless_told_otherwise(tmp_path):
    """Run from a shell that sets no thread count, doodle's BLAS uses one thread (its
    matrices are small: OpenBLAS's thread per core only spun, 0.72 s of CPU instead of 0.44 s
    for a 60 s doodle's compile); a thread count the user sets is kept."""
    import os

    probe = ("from doodle.app.cli.main import main; main(['info', 'missing.doodle']); "
             "import numpy, threadpoolctl; "
             "print(max(i['num_threads'] for i in threadpoolctl.threadpool_info() if i['user_api'] == 'blas'))")
    env = {k: v for k, v in os.environ.items() if k not in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS")}
    threads = subprocess.run([sys.executable, "-c", probe], env=env, cwd=tmp_path, capture_output=True, text=True)
    assert threads.stdout.split()[-1] == "1", threads.stderr
    env["OPENBLAS_NUM_THREADS"] = "2"
    threads = subprocess.run([sys.executable, "-c", probe], env=env, cwd=tmp_path, capture_output=True, text=True)
    assert threads.stdout.split()[-1] == "2", threads.stderr
