import os
import signal
import subprocess
import sys
import textwrap
import time
import warnings
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from doodle.input import fileformat
from doodle.core.errors import DoodleError
from doodle.input.fileformat import DoodleWriter, read_doodle, write_doodle
from doodle.core.model import Doodle, Track

REPO = Path(__file__).resolve().parents[1]

HEADER = """\
# doodle 1
# device vive-controller
# rate 90
# units m
# convention openvr
# track c0 role=right_hand serial=LHR-1A2B3C4D
# track c1 role=left_hand
# x-note any free text
t,c0.ok,c0.px,c0.py,c0.pz,c0.qx,c0.qy,c0.qz,c0.qw,c1.ok,c1.px,c1.py,c1.pz,c1.qx,c1.qy,c1.qz,c1.qw
"""
ROWS = [
    "0.000000,1,0.258747,0.378101,-0.036361,0.393373,-0.011139,0.107187,0.913041,1,0.1,0.2,0.3,0,0,0,1",
    "0.011111,1,0.259000,0.378000,-0.036000,0.393373,-0.011139,0.107187,0.913041,0,nan,nan,nan,nan,nan,nan,nan",
    "0.022222,1,0.260000,0.379000,-0.035000,0.393373,-0.011139,0.107187,0.913041,0,1,2,3,4,5,6,7",
    "0.033333,1,0.261000,0.380000,-0.034000,0.393373,-0.011139,0.107187,0.913041,1,0.1,0.2,0.3,0,0,0,1",
]
FIRST_ROW_LINE = 10  # 1-based line number of ROWS[0]


def _write(tmp_path, text, name="rec.doodle"):
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def _doodle(n=50, seed=0, invalid=True):
    rng = np.random.default_rng(seed)
    t = np.cumsum(rng.uniform(0.009, 0.013, n))
    t -= t[0]
    tracks = []
    for k, (role, serial) in enumerate([("right_hand", "LHR-1"), ("left_hand", "")]):
        p = rng.normal(size=3) + np.cumsum(rng.normal(scale=0.01, size=(n, 3)), axis=0)  # a hand moves: no jumps
        q = Rotation.random(n, random_state=seed + k).as_quat()
        valid = np.ones(n, bool)
        if invalid:
            valid[rng.choice(n, 7, replace=False)] = False
            p[~valid] = np.nan
            q[~valid] = np.nan
        tracks.append(Track(f"c{k}", t, p, q, valid, role=role, serial=serial))
    return Doodle(tuple(tracks), 90.0, "vive-controller", meta={"x-note": "hello world"})


def _assert_same(a: Doodle, b: Doodle, tol=1e-6):
    assert a.names == b.names
    for ta, tb in zip(a.tracks, b.tracks):
        np.testing.assert_allclose(ta.t, tb.t, atol=tol)
        np.testing.assert_array_equal(ta.valid, tb.valid)
        v = ta.valid
        np.testing.assert_allclose(ta.p[v], tb.p[v], atol=tol)
        np.testing.assert_allclose(ta.q[v], tb.q[v], atol=tol)
        assert np.isnan(tb.p[~v]).all() and np.isnan(tb.q[~v]).all()
        assert (ta.role, ta.serial) == (tb.role, tb.serial)


# --------------------------------------------------------------------------- loading


def test_load_example(tmp_path):
    path = _write(tmp_path, HEADER + "\n".join(ROWS) + "\n")
    d = read_doodle(path)
    assert d.source == str(path)
    assert d.device == "vive-controller" and d.rate == 90.0
    assert d.meta == {"x-note": "any free text"}
    assert d.names == ["c0", "c1"]
    c0, c1 = d.tracks
    assert (c0.role, c0.serial) == ("right_hand", "LHR-1A2B3C4D")
    assert (c1.role, c1.serial) == ("left_hand", "")
    assert c0.t is c1.t
    np.testing.assert_allclose(c0.t, [0, 0.011111, 0.022222, 0.033333])
    # openvr -> ours: x and z flip; quaternion (-qx, qy, -qz, qw), renormalised
    np.testing.assert_allclose(c0.p[0], [-0.258747, 0.378101, 0.036361])
    q = np.array([-0.393373, -0.011139, -0.107187, 0.913041])
    np.testing.assert_allclose(c0.q[0], q / np.linalg.norm(q))
    np.testing.assert_array_equal(c1.valid, [True, False, False, True])
    assert np.isnan(c1.p[1:3]).all() and np.isnan(c1.q[1:3]).all()  # ok=0 with finite values -> NaN


def test_times_kept_relative_to_first_sample(tmp_path):
    rows = [r.replace("0.0", "100.0", 1) for r in ROWS]
    d = read_doodle(_write(tmp_path, HEADER + "\n".join(rows) + "\n"))
    np.testing.assert_allclose(d.t, [0, 0.011111, 0.022222, 0.033333], atol=1e-9)


def test_units_cm_and_mm(tmp_path):
    for units, scale in (("cm", 0.01), ("mm", 0.001)):
        text = HEADER.replace("# units m", f"# units {units}").replace("openvr", "doodle")
        d = read_doodle(_write(tmp_path, text + "\n".join(ROWS) + "\n"))
        np.testing.assert_allclose(d.tracks[0].p[0], np.array([0.258747, 0.378101, -0.036361]) * scale)


def test_quaternion_renormalised(tmp_path):
    rows = list(ROWS)
    rows[0] = rows[0].replace(",0,0,0,1", ",0,0,0,1.05")
    d = read_doodle(_write(tmp_path, HEADER + "\n".join(rows) + "\n"))
    np.testing.assert_allclose(d.tracks[1].q[0], [0, 0, 0, 1])


def test_crlf_file_loads(tmp_path):
    path = tmp_path / "crlf.doodle"
    path.write_bytes((HEADER + "\n".join(ROWS) + "\n").replace("\n", "\r\n").encode())
    assert len(read_doodle(path).t) == 4


# --------------------------------------------------------------------------- round trips


@pytest.mark.parametrize("convention", ["doodle", "unity", "openvr"])
def test_round_trip(tmp_path, convention):
    d = _doodle()
    path = tmp_path / "rt.doodle"
    write_doodle(path, d, convention=convention)
    text = path.read_text()
    assert text.startswith("# doodle 1\n") and f"# convention {convention}\n" in text
    assert ",0,nan,nan,nan,nan,nan,nan,nan" in text
    back = read_doodle(path)
    _assert_same(d, back)
    assert back.meta == {"x-note": "hello world"}
    assert back.rate == 90.0 and back.device == "vive-controller"


def test_round_trip_writer_units_cm(tmp_path):
    d = _doodle(n=40)
    path = tmp_path / "cm.doodle"
    tracks = [(tr.name, tr.role, tr.serial) for tr in d.tracks]
    with DoodleWriter(path, tracks, 90, "vive-controller", convention="openvr", units="cm") as w:
        for i, t in enumerate(d.t):
            w.append(t, [(tr.p[i], tr.q[i], bool(tr.valid[i])) for tr in d.tracks])
    assert "# units cm\n" in path.read_text()
    back = read_doodle(path)
    _assert_same(d, back)
    # values in the file are centimetres in OpenVR's frame
    first = path.read_text().splitlines()[8].split(",")
    if d.tracks[0].valid[0]:
        assert float(first[2]) == pytest.approx(-100 * d.tracks[0].p[0, 0], abs=1e-5)


def test_write_rejects_valid_nan_and_unshared_clock(tmp_path):
    d = _doodle(invalid=False)
    bad = Track("c0", d.t, np.full((len(d.t), 3), np.nan), d.tracks[0].q, np.ones(len(d.t), bool))
    with pytest.raises(DoodleError, match="c0"):
        write_doodle(tmp_path / "x.doodle", Doodle((bad,), 90.0))
    other = Track("c1", d.t + 0.001, d.tracks[1].p, d.tracks[1].q, d.tracks[1].valid)
    with pytest.raises(DoodleError, match="clock"):
        write_doodle(tmp_path / "x.doodle", Doodle((d.tracks[0], other), 90.0))
    assert not (tmp_path / "x.doodle").exists()


def test_atomic_write_keeps_existing_file(tmp_path, monkeypatch):
    path = tmp_path / "keep.doodle"
    path.write_text("precious\n")

    def failing_rows(rows, n_tracks, chunk=20000):
        yield "0.000000,1,0.1,0.2"
        raise RuntimeError("disk on fire")

    monkeypatch.setattr(fileformat, "format_rows", failing_rows)
    with pytest.raises(RuntimeError, match="disk on fire"):
        write_doodle(path, _doodle())
    assert path.read_text() == "precious\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["keep.doodle"]  # no temp file left


def test_writer_refuses_to_overwrite(tmp_path):
    path = tmp_path / "old.doodle"
    path.write_text("precious\n")
    with pytest.raises(DoodleError, match="exists"):
        DoodleWriter(path, ["c0"], 90, "vive")
    assert path.read_text() == "precious\n"


def test_writer_rejects_bad_appends(tmp_path):
    with DoodleWriter(tmp_path / "w.doodle", ["c0"], 90, "vive") as w:
        w.append(0.0, [((0, 0, 0), (0, 0, 0, 1), True)])
        with pytest.raises(DoodleError, match="after"):
            w.append(0.0, [((0, 0, 0), (0, 0, 0, 1), True)])
        with pytest.raises(DoodleError, match="unit"):
            w.append(0.1, [((0, 0, 0), (0, 0, 0, 0), True)])
        with pytest.raises(DoodleError, match="poses"):
            w.append(0.1, [])
        w.append(0.1, [(None, None, False)])
    d = read_doodle(tmp_path / "w.doodle")
    np.testing.assert_array_equal(d.tracks[0].valid, [True, False])


# --------------------------------------------------------------------------- cut-off files


def test_truncated_last_line_warns_and_loads_whole_rows(tmp_path):
    text = HEADER + "\n".join(ROWS) + "\n" + ROWS[0].replace("0.000000", "0.044444")[:40]
    path = _write(tmp_path, text)
    with pytest.warns(UserWarning, match=rf"{path.name}:{FIRST_ROW_LINE + 4}: last row is incomplete.*loaded 4"):
        d = read_doodle(path)
    assert len(d.t) == 4


def test_truncated_mid_number_warns(tmp_path):
    path = _write(tmp_path, HEADER + "\n".join(ROWS) + "\n0.044444,1,0.2,0.3,0.4,0,0,0,1,0,na")
    with pytest.warns(UserWarning, match="incomplete"):
        assert len(read_doodle(path).t) == 4


def test_last_line_without_newline_that_parses_is_kept(tmp_path):
    path = _write(tmp_path, HEADER + "\n".join(ROWS))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert len(read_doodle(path).t) == 4


def test_bad_line_before_the_last_is_an_error(tmp_path):
    rows = list(ROWS)
    rows[2] = rows[2][:30]
    path = _write(tmp_path, HEADER + "\n".join(rows))
    with pytest.raises(DoodleError, match=rf"{path.name}:{FIRST_ROW_LINE + 2}"):
        read_doodle(path)


# --------------------------------------------------------------------------- errors

HEADER_LINES = HEADER.splitlines()


def _header_without(key):
    return "\n".join(line for line in HEADER_LINES if not line.startswith(f"# {key}")) + "\n"


def _header_with(old, new):
    return HEADER.replace(old, new)


def _rows_with(i, new):
    rows = list(ROWS)
    rows[i] = new
    return rows


HEADER_ERRORS = [
    # (header text, line, words in the message)
    (_header_with("# doodle 1", "# doodle 2"), 1, "supported"),
    (_header_with("# doodle 1", "hello"), 1, "not a doodle file"),
    (_header_with("# x-note", "# color blue\n# x-note"), 8, "unknown header key 'color'"),
    (_header_with("# units m", "# units m\n# units cm"), 5, "duplicate"),
    (_header_with("# x-note any", "# x-note any\n# x-note"), 9, "duplicate"),
    (_header_without("rate"), 8, "rate"),
    (_header_without("device"), 8, "device"),
    (_header_with("# rate 90", "# rate 0"), 3, "rate"),
    (_header_with("# rate 90", "# rate fast"), 3, "rate"),
    (_header_with("# units m", "# units in"), 4, "units"),
    (_header_with("# convention openvr", "# convention maya"), 5, "unity"),
    (_header_with("# track c1 role=left_hand", "# track c0"), 7, "duplicate track"),
    (_header_with("# track c1 role=left_hand", "# track c1 hand=left"), 7, "hand=left"),
    (_header_with("# track c1 role=left_hand", "# track c/1"), 7, "track name"),
    (_header_with("t,c0.ok,c0.px", "t,c0.ok,c0.pz"), 9, "c0.px"),
    (_header_with(",c1.qw\n", "\n"), 9, "c1.qw"),
    (_header_with(",c1.qw\n", ",c1.qw,extra\n"), 9, "extra"),
    (_header_with("c0.px,c0.py", "c0.py,c0.px"), 9, "c0.px"),
]


@pytest.mark.parametrize("header,line,words", HEADER_ERRORS)
def test_header_errors(tmp_path, header, line, words):
    path = _write(tmp_path, header + "\n".join(ROWS) + "\n")
    with pytest.raises(DoodleError) as err:
        read_doodle(path)
    msg = str(err.value)
    assert f"{path.name}:{line}" in msg
    assert words in msg


def test_no_tracks(tmp_path):
    header = "\n".join(line for line in HEADER_LINES[:5] + HEADER_LINES[7:8]) + "\nt\n"
    path = _write(tmp_path, header + "0\n1\n")
    with pytest.raises(DoodleError, match=rf"{path.name}:7: .*no track"):
        read_doodle(path)


L = FIRST_ROW_LINE
ROW_ERRORS = [
    (_rows_with(1, ROWS[1][:-4]), L + 1, "c1.qw"),  # field missing
    (_rows_with(1, ROWS[1] + ",1"), L + 1, "extra"),
    (_rows_with(2, ROWS[2].replace("0.260000", "0.26x")), L + 2, "column c0.px"),
    (_rows_with(2, ROWS[2].replace("0.260000", "")), L + 2, "column c0.px"),
    (_rows_with(2, ROWS[2].replace("0.260000", "inf")), L + 2, "column c0.px"),
    (_rows_with(3, ROWS[3].replace(",1,0.1,", ",2,0.1,")), L + 3, "c1.ok"),
    (_rows_with(0, ROWS[0].replace("0.1,0.2,0.3", "0.1,nan,0.3")), L, "track c1"),
    (_rows_with(0, ROWS[0].replace(",0,0,0,1", ",0,0,0,0")), L, "track c1: zero quaternion"),
    (_rows_with(0, ROWS[0].replace(",0,0,0,1", ",0,0,0,1.2")), L, "track c1"),
    (_rows_with(3, ROWS[3].replace("0.033333", "0.022222")), L + 3, "0.022222"),
    (_rows_with(3, ROWS[3].replace("0.033333", "0.015")), L + 3, "0.015000"),
    (_rows_with(3, ROWS[3].replace("0.033333", "nan")), L + 3, "time"),
    (ROWS[:2] + [""] + ROWS[2:], L + 2, "blank"),
]


@pytest.mark.parametrize("rows,line,words", ROW_ERRORS)
def test_row_errors(tmp_path, rows, line, words):
    path = _write(tmp_path, HEADER + "\n".join(rows) + "\n")
    with pytest.raises(DoodleError) as err:
        read_doodle(path)
    msg = str(err.value)
    assert f"{path.name}:{line}" in msg
    assert words in msg


def test_time_error_names_both_times_and_lines(tmp_path):
    rows = _rows_with(3, ROWS[3].replace("0.033333", "0.015"))
    path = _write(tmp_path, HEADER + "\n".join(rows) + "\n")
    with pytest.raises(DoodleError) as err:
        read_doodle(path)
    msg = str(err.value)
    assert "0.015000" in msg and "0.022222" in msg and f"line {L + 2}" in msg


@pytest.mark.parametrize("rows,words", [([], "no samples"), (ROWS[:1], "at least two samples")])
def test_too_few_rows(tmp_path, rows, words):
    path = _write(tmp_path, HEADER + "".join(r + "\n" for r in rows))
    with pytest.raises(DoodleError, match=words) as err:
        read_doodle(path)
    assert path.name in str(err.value)


def test_error_deep_in_a_large_file_is_located(tmp_path):
    d = _doodle(n=5000, invalid=False)
    path = tmp_path / "big.doodle"
    write_doodle(path, d)
    lines = path.read_text().split("\n")
    k = 4321
    fields = lines[k].split(",")
    fields[12] = "oops"  # c1.pz
    lines[k] = ",".join(fields)
    path.write_text("\n".join(lines))
    with pytest.raises(DoodleError) as err:
        read_doodle(path)
    assert f"big.doodle:{k + 1}: column c1.pz" in str(err.value)


# --------------------------------------------------------------------------- crash safety

CHILD = textwrap.dedent(
    """
    import os, sys, time
    sys.path.insert(0, sys.argv[1])
    from doodle.input.fileformat import DoodleWriter
    path, progress = sys.argv[2], sys.argv[3]
    fd = os.open(progress, os.O_WRONLY | os.O_CREAT | os.O_APPEND)
    with DoodleWriter(path, [("c0", "right_hand", "S1"), ("c1", "", "")], 90, "synthetic") as w:
        i = 0
        while True:
            t = i / 90
            p = (0.01 * i, 1.0, -0.5)
            w.append(t, [(p, (0.0, 0.0, 0.0, 1.0), True), (p, (0.0, 0.6, 0.0, 0.8), i % 10 != 0)])
            os.write(fd, b"%d\\n" % i)
            i += 1
            time.sleep(0.002)
    """
)


def test_writer_survives_sigkill(tmp_path):
    path, progress = tmp_path / "live.doodle", tmp_path / "progress"
    proc = subprocess.Popen([sys.executable, "-c", CHILD, str(REPO), str(path), str(progress)])
    try:
        deadline = time.monotonic() + 30
        written = -1
        while time.monotonic() < deadline and written < 4 * 90:  # at least 4 s of samples
            time.sleep(0.05)
            if progress.exists():
                done = progress.read_text().split("\n")[:-1]
                written = int(done[-1]) if done else -1
            assert proc.poll() is None, "child died on its own"
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait(10)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(10)
    rows_appended = len(progress.read_text().split("\n")) - 1  # rows fully appended before the kill
    assert rows_appended >= 4 * 90
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the kill may cut the last line
        d = read_doodle(path)
    n = len(d.t)
    assert n >= rows_appended - 91 - 1  # lost at most ~1 s (+ the row being written)
    np.testing.assert_allclose(d.t, np.arange(n) / 90, atol=1e-6)
    np.testing.assert_allclose(d.tracks[0].p[:, 0], 0.01 * np.arange(n), atol=1e-6)
    assert d.tracks[1].valid.sum() == n - len(range(0, n, 10))


def test_writer_syncs_about_once_per_second_of_samples(tmp_path, monkeypatch):
    synced_at = []
    real_fsync = os.fsync
    writer_ref = {}

    def counting_fsync(fd):
        synced_at.append(writer_ref["w"]._last_t if "w" in writer_ref else None)
        real_fsync(fd)

    monkeypatch.setattr(fileformat.os, "fsync", counting_fsync)
    w = DoodleWriter(tmp_path / "s.doodle", ["c0"], 90, "vive")
    writer_ref["w"] = w
    for i in range(10 * 90):
        w.append(i / 90, [((0, 0, 0), (0, 0, 0, 1), True)])
    during = list(synced_at)
    w.close()
    # header, first row, then once per second of sample time: 1 + 1 + 9
    assert len(during) == 11
    gaps = np.diff([s for s in during if s is not None])
    assert (gaps >= 1.0 - 1e-9).all() and (gaps < 1.0 + 1.5 / 90).all()
    assert len(synced_at) == 12  # and on close
