"""Broken and absurd inputs through the command line: one located line ``doodle: error: …``
and exit 1 for what cannot be read, a located warning for what is repaired — never numpy's
own diagnosis, a traceback or an overflow warning."""

import json
import warnings
from pathlib import Path

import numpy as np
import pytest

from doodle.app.cli.main import main
from doodle.input.repair import MAX_RADIUS, MAX_SPEED, impossible

ROOT = Path(__file__).resolve().parents[1]
DEMO = ROOT / "examples" / "demo.doodle"


def cli(capsys, *args):
    """``(exit code, stdout, stderr lines)`` of ``doodle ARGS``, numpy warnings made errors."""
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        code = main([str(a) for a in args])
    out, err = capsys.readouterr()
    return code, out, err.splitlines()


def refused(capsys, *args) -> str:
    """The one error line of a command that must refuse its input."""
    code, _, err = cli(capsys, *args)
    assert code == 1 and len(err) == 1 and err[0].startswith("doodle: error: "), err
    assert "Traceback" not in err[0] and "allow_pickle" not in err[0], err
    return err[0]


def edited(tmp_path, name, changes: dict) -> Path:
    """The demo doodle with fields changed: ``{(line, column index): text}``."""
    lines = DEMO.read_text().split("\n")
    for (lineno, col), text in changes.items():
        fields = lines[lineno - 1].split(",")
        fields[col] = text
        lines[lineno - 1] = ",".join(fields)
    path = tmp_path / name
    path.write_text("\n".join(lines))
    return path


# --------------------------------------------------------------------------- .npz and meshes


def test_random_bytes_are_not_an_npz_archive(tmp_path, capsys):
    junk = tmp_path / "junk.npz"
    junk.write_bytes(np.random.default_rng(0).bytes(3000))
    message = f"{junk}: not a valid .npz archive (not a zip archive)"
    assert message in refused(capsys, "compile", DEMO, "-o", tmp_path / "o", "--effort-model", junk)
    line = refused(capsys, "compile", DEMO, "-o", tmp_path / "o", "--terrain", f"heightfield:{junk}")
    assert f"height field file '{junk}': not a valid .npz archive (not a zip archive)" in line
    lib = tmp_path / "lib"
    lib.mkdir()
    (lib / "junk.npz").write_bytes(junk.read_bytes())  # a library's shapes lie inside it
    (lib / "library.toml").write_text('[library]\nname = "mine"\n\n[[actions]]\nname = "Wave"\n'
                                      'expression = "T_X T_N_X"\nshape = "junk.npz"\n')
    line = refused(capsys, "recognize", "--library", lib, DEMO)
    assert f"{lib / 'junk.npz'} (shape of action 'Wave'): not a valid .npz archive (not a zip archive)" in line


def test_object_arrays_are_refused_unloaded(tmp_path, capsys):
    path = tmp_path / "objects.npz"
    np.savez(path, heights=np.array([{"x": 1}], dtype=object))
    line = refused(capsys, "compile", DEMO, "-o", tmp_path / "o", "--terrain", f"heightfield:{path}")
    assert "objects.npz': not a valid .npz archive (array 'heights' holds Python objects, which this program never " \
           "loads)" in line


def test_a_junk_obj_mesh_names_its_line(tmp_path, capsys):
    mesh = tmp_path / "ground.obj"
    mesh.write_text("# ground\nv 0 0 0\nv 1 0 0 0 1\nv 0 0 1\nf 1 2 3\n")
    line = refused(capsys, "compile", DEMO, "-o", tmp_path / "o", "--terrain", f"mesh:{mesh}")
    assert f"{mesh}:3: a vertex is 'v x y z'" in line
    mesh.write_text("v 0 0 0\nv 1 0 0\nv 0 0 1\nf 1 2 4\n")
    assert f"{mesh}:4: face vertex 4 does not exist (3 vertices so far)" in refused(
        capsys, "compile", DEMO, "-o", tmp_path / "o", "--terrain", f"mesh:{mesh}")
    mesh.write_bytes(np.random.default_rng(1).bytes(2000))
    assert f"{mesh}:" in refused(capsys, "compile", DEMO, "-o", tmp_path / "o", "--terrain", f"mesh:{mesh}")


def test_effort_models_are_checked_field_by_field(tmp_path, capsys):
    from laban.models import DEFAULT

    with np.load(DEFAULT, allow_pickle=False) as z:
        arrays = {k: z[k] for k in z.files}
    cases = {"negative.npz": ("drive_variances", -0.5, "'drive_variances' holds -0.5"),
             "nan.npz": ("nb_time_means", np.nan, "'nb_time_means' holds nan"),
             "huge.npz": ("element_centre", 1e308, "'element_centre' holds 1e+308")}
    for name, (key, value, said) in cases.items():
        changed = dict(arrays)
        changed[key] = changed[key].copy()
        changed[key].flat[1] = value
        np.savez(tmp_path / name, **changed)
        line = refused(capsys, "compile", DEMO, "-o", tmp_path / "o", "--effort-model", tmp_path / name)
        assert f"{tmp_path / name}: array {said}" in line, line
    np.savez(tmp_path / "shape.npz", **dict(arrays, drive_start=arrays["drive_start"][:5]))
    line = refused(capsys, "compile", DEMO, "-o", tmp_path / "o", "--effort-model", tmp_path / "shape.npz")
    assert "shape.npz: array 'drive_start' must be numbers shaped 8×n, got float64 (5, 6)" in line
    meta = json.loads(str(arrays["meta"]))
    np.savez(tmp_path / "labels.npz", **dict(arrays, meta=np.array(json.dumps(dict(meta, drive_labels=["Punch"])))))
    line = refused(capsys, "compile", DEMO, "-o", tmp_path / "o", "--effort-model", tmp_path / "labels.npz")
    assert "labels.npz: 'drive_labels' must list each of Punch, Dab" in line


# --------------------------------------------------------------------------- doodle files


def test_a_nan_in_a_tracked_sample_names_line_and_column(tmp_path, capsys):
    path = edited(tmp_path, "nan.doodle", {(300, 3): "nan"})
    assert refused(capsys, "tokens", path) == (f"doodle: error: {path}:300: column c0.py: track c0: nan in a sample "
                                               "marked tracked (every value of a tracked sample must be a finite number)")
    path = edited(tmp_path, "norm.doodle", {(300, 5): "7"})
    assert f"{path}:300: column c0.qx…c0.qw: track c0: quaternion norm" in refused(capsys, "tokens", path)


def _recognised(capsys, path):
    code, out, err = cli(capsys, "recognize", path)
    assert code == 0
    return out.splitlines()[1:], err


@pytest.mark.parametrize("changes, column, said", [
    ({(200, 2): "1e308"}, "c0.px", "1e+308 m is beyond any tracked space"),
    ({(300, 3): "1000"}, "c0.py", "1000 m is beyond any tracked space"),
    ({(300, 3): "5", (301, 3): "5.01"}, "c0.py", "a jump of 5 m at 428 m/s from line 299, faster than any hand"),
    ({(8, 4): "-3"}, "c0.pz", "a jump of 3 m at 255 m/s from line 9, faster than any hand"),  # the first sample
])
def test_impossible_samples_are_lost_tracking(tmp_path, capsys, changes, column, said):
    """A spike no hand could make is repaired as lost tracking, with a warning naming its
    line and column, and the doodle reads as it did without it (it used to read as an
    extra gesture, or an unknown one after six overflow warnings)."""
    expected, _ = _recognised(capsys, DEMO)
    path = edited(tmp_path, "spike.doodle", changes)
    got, err = _recognised(capsys, path)
    assert got == expected
    first = min(changes)[0]
    assert len(err) == 1 and err[0].startswith(f"doodle: warning: {path}:{first}: column {column}: track c0: {said}")
    assert f"{len(changes)} impossible sample" in err[0] and "treated as lost tracking" in err[0]


def test_what_is_impossible():
    t = np.arange(200) / 90.0
    p = np.column_stack([np.sin(t), np.cos(2 * t), 0.5 * t])  # a hand at under 2 m/s
    valid = np.ones(len(t), bool)
    assert not impossible(t, p, valid).any()
    spiky = p.copy()
    spiky[[0, 50, 51, 120]] += [[1, 0, 0], [0, 2, 0], [0, 2, 0], [0, 0, MAX_RADIUS * 2]]
    assert list(np.flatnonzero(impossible(t, spiky, valid))) == [0, 50, 51, 120]
    jumped = p.copy()
    jumped[100:] += [1.0, 0, 0]  # tracking re-localised 1 m away: flagged until a hand could be there
    assert list(np.flatnonzero(impossible(t, jumped, valid))) == list(range(100, 100 + int(90 / MAX_SPEED)))
    lost = valid.copy()
    lost[50:52] = False  # samples already lost are not judged
    assert list(np.flatnonzero(impossible(t, spiky, lost))) == [0, 120]


def test_real_recordings_have_no_impossible_samples(vive_files):
    from doodle.input.csvimport import read_csv

    for path in vive_files:
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            doodle = read_csv(path, convention="unity")
        assert all(tr.valid.all() for tr in doodle.tracks), path


def lost(tmp_path, name, start: float, end: float, fields: dict) -> Path:
    """The demo doodle with ``fields`` (``{column index: text}``) set on every row whose time
    is in [start, end) s: tracking lost (``{1: "0", 2: "nan", …}``) or sent far away."""
    lines = DEMO.read_text().split("\n")
    changes = {}
    for lineno, line in enumerate(lines, 1):
        if line and not line.startswith(("#", "t,")) and start <= float(line.split(",")[0]) < end:
            changes.update({(lineno, col): text for col, text in fields.items()})
    assert len(changes) > 10 * len(fields)
    return edited(tmp_path, name, changes)


LOST = {1: "0", **{c: "nan" for c in range(2, 9)}}  # c0.ok = 0, pose unknown
FAR = {2: "500", 3: "-500"}  # c0.px, c0.py: tracking lost somewhere far away


@pytest.mark.parametrize("fields, span, extra", [
    (LOST, (3.0, 3.3), []),  # a gap within --max-gap (0.5 s)
    (FAR, (3.0, 3.3), []),
    (LOST, (0.0, 1.0), []),  # untracked at the ends: the nearest tracked pose
    (LOST, (7.0, 99.0), []),
    (LOST, (3.0, 5.0), ["--max-gap", "3"]),  # a long gap the user asks to repair
    (FAR, (3.0, 5.0), ["--max-gap", "3"]),
])
def test_lost_tracking_compiles_as_repaired(tmp_path, capsys, fields, span, extra):
    """Lost tracking — flagged, or positions far beyond any tracked space — is repaired for
    the whole compile as the Segmenter repairs it (the path and the Effort read the poses
    too: they used to get the NaN and stop at "internal error: ValueError: `y` must contain
    only finite values")."""
    path = lost(tmp_path, "lost.doodle", *span, fields)
    code, _, err = cli(capsys, "compile", path, "-o", tmp_path / "out", *extra)
    assert code == 0, err
    assert not [e for e in err if "error" in e or "Traceback" in e], err
    if fields is FAR:
        assert len(err) == 1 and err[0].startswith(f"doodle: warning: {path}:") and "track c0" in err[0] \
            and "treated as lost tracking" in err[0], err
    assert (tmp_path / "out" / "c0.bvh").stat().st_size > 0


@pytest.mark.parametrize("fields", [LOST, FAR])
def test_a_long_loss_of_tracking_is_refused_by_track_and_time_leaving_the_output(tmp_path, capsys, fields):
    """Two seconds lost (beyond --max-gap): one line naming the file, track and time span,
    exit 1, and the output of an earlier compile (and the user's own files) left as they were."""
    out = tmp_path / "out"
    assert cli(capsys, "compile", DEMO, "-o", out)[0] == 0
    (out / "mine.txt").write_text("mine\n")
    before = {f.name: f.read_bytes() for f in out.iterdir()}
    path = lost(tmp_path, "lost.doodle", 3.0, 5.0, fields)
    code, _, err = cli(capsys, "compile", path, "-o", out)
    line = err[-1]
    assert code == 1 and line.startswith(f"doodle: error: {path}: track c0 lost tracking for 2.01 s (3.00-5.01 s), "
                                         "more than the 0.5 s that are repaired"), err
    assert not [e for e in err if "Traceback" in e or "internal error" in e], err
    assert {f.name: f.read_bytes() for f in out.iterdir()} == before


def test_effort_classify_reads_repaired_poses(tmp_path, capsys):
    """``doodle laban classify`` reads the hand's poses too: a short loss is repaired; a long
    one is that file's error, and the next file is still classified."""
    short = lost(tmp_path, "short.doodle", 3.0, 3.3, LOST)
    code, out, err = cli(capsys, "laban", "classify", short)
    assert code == 0 and not err and "Walk" in out, err
    long = lost(tmp_path, "long.doodle", 3.0, 5.0, LOST)
    code, out, err = cli(capsys, "laban", "classify", long, DEMO)
    assert code == 1 and err == [f"doodle: error: {long}: track c0 lost tracking for 2.01 s (3.00-5.01 s), more than "
                                 "the 0.5 s that are repaired; trim the doodle or raise --max-gap"], err
    assert str(DEMO) in out


def test_repaired_fills_every_pose_and_keeps_the_flags():
    from doodle.core.model import Doodle, Track
    from doodle.input.repair import fill_gaps, repaired

    t = np.arange(100) / 90.0
    p = np.column_stack([np.sin(t), np.cos(t), t])
    q = np.tile([0.0, 0.0, 0.0, 1.0], (100, 1))
    valid = np.ones(100, bool)
    whole = Doodle((Track("a", t, p, q, valid),), 90.0)
    assert repaired(whole, 0.5) is whole
    valid = valid.copy()
    valid[[0, 1, 40, 41, 42, 99]] = False
    holey = Track("a", t, np.where(valid[:, None], p, np.nan), np.where(valid[:, None], q, np.nan), valid)
    fixed = repaired(Doodle((holey,), 90.0), 0.5).tracks[0]
    assert np.isfinite(fixed.p).all() and np.isfinite(fixed.q).all()
    assert (fixed.valid == valid).all()
    expected = fill_gaps("a", t, holey.p, holey.q, valid, 0.5)
    assert np.array_equal(fixed.p, expected[0]) and np.array_equal(fixed.q, expected[1])
    again = fill_gaps("a", t, fixed.p, fixed.q, valid, 0.5)  # the Segmenter repairs it again: no change
    assert np.array_equal(again[0], fixed.p) and np.array_equal(again[1], fixed.q)


# --------------------------------------------------------------------------- CSV cut off


def _csv(tmp_path, name, rows=None) -> Path:
    """The demo as a CSV of the vive-gestures layout (openvr convention), optionally cut."""
    lines = DEMO.read_text().splitlines()
    data = [line.split(",") for line in lines[7:]]
    text = ["t,c0_px,c0_py,c0_pz,c0_qx,c0_qy,c0_qz,c0_qw"] + [",".join([f[0]] + f[2:]) for f in data]
    path = tmp_path / name
    path.write_text("\n".join(text[:rows]) + "\n")
    return path


def test_a_csv_cut_off_mid_line_loads_its_whole_rows(tmp_path, capsys):
    whole = _csv(tmp_path, "whole.csv")
    cut = tmp_path / "cut.csv"
    cut.write_bytes(whole.read_bytes()[:-30])  # the crash: the last row half written, no newline
    code, out, err = cli(capsys, "info", "--convention", "openvr", cut)
    rows = len(whole.read_text().splitlines()) - 1
    assert code == 0 and f"{rows - 1} samples" in out
    assert err == [f"doodle: warning: {cut}:{rows + 1}: last row is incomplete (cut off?); loaded {rows - 1} whole rows"]


def test_a_malformed_csv_line_before_the_last_is_an_error(tmp_path, capsys):
    whole = _csv(tmp_path, "whole.csv").read_text().splitlines()
    broken = tmp_path / "broken.csv"
    broken.write_text("\n".join(whole[:100] + ["1.0,2.0,3.0"] + whole[100:]))  # no final newline either
    assert refused(capsys, "info", "--convention", "openvr", broken) == f"doodle: error: {broken}:101: 3 fields, expected 8"
    broken.write_text("\n".join(whole[:-1] + [whole[-1] + ",1"]) + "\n")  # a last line ended, but wrong
    assert refused(capsys, "info", "--convention", "openvr", broken) == \
        f"doodle: error: {broken}:{len(whole)}: 9 fields, expected 8"


def test_effort_classify_reads_csv_recordings_with_their_convention(tmp_path, capsys, vive_files):
    """``doodle laban classify`` takes a real Vive CSV as every other command does: its
    convention asked for, then given (``--convention``, ``--tracks``); a hand that stayed
    put is said to be left neutral and why; a CSV given to training is told how to get a
    label."""
    real = vive_files[0]
    assert refused(capsys, "laban", "classify", "--whole", real) == (
        f"doodle: error: {real}: a CSV file does not say its coordinate convention; pass --convention unity, "
        "openvr or doodle")
    code, out, err = cli(capsys, "laban", "classify", "--whole", "--convention", "unity", "--tracks", "c0", real)
    assert code == 0 and not err and "P sudden" in out and out.count("(whole)") == 1, (out, err)
    still = tmp_path / "still.csv"
    t = np.arange(0, 2, 1 / 90)
    rows = [f"{x:.4f},{0.01 * np.sin(x):.5f},1.2,0.3,0,0,0,1" for x in t]  # 1 cm of drift in 2 s
    still.write_text("t,c0_px,c0_py,c0_pz,c0_qx,c0_qy,c0_qz,c0_qw\n" + "\n".join(rows) + "\n")
    code, out, err = cli(capsys, "laban", "classify", "--whole", "--convention", "unity", still)
    assert code == 0 and "(whole)" in out and "neutral, not read: still (within 3 cm and 11°)" in out, out
    assert refused(capsys, "laban", "train", str(real), "-o", str(tmp_path / "m.npz")) == (
        f"doodle: error: {real}: only doodle files carry a Drive label; convert it with `doodle import` and label "
        "it with `doodle laban label`")


def test_render_takes_csv_input_options():
    from doodle.app.cli.main import build_parser

    args = build_parser().parse_args(["render", "take.csv", "-o", "take.png", "--convention", "unity", "--tracks", "c0"])
    assert (args.convention, args.tracks) == ("unity", "c0")
