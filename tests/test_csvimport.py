from pathlib import Path

import numpy as np
import pytest

from doodle.input.csvimport import parse_column_map, read_csv
from doodle.core.errors import DoodleError

DATA = Path(__file__).resolve().parents[1] / ".." / "shared" / "data" / "vive-gestures"

HEAD = "t,c0_px,c0_py,c0_pz,c0_qx,c0_qy,c0_qz,c0_qw,c1_px,c1_py,c1_pz,c1_qx,c1_qy,c1_qz,c1_qw"
ROWS = [
    "0.000000,0.1,0.7,-1.5,0,0,0,1,-0.2,0.7,-1.5,0,0,0,1",
    "0.011000,0.2,0.8,-1.4,0,0,0,1,-0.2,0.7,-1.5,0,0,0,1",
    "0.022000,0.3,0.9,-1.3,0,0,0,1,nan,0.7,-1.5,0,0,0,1",
    "0.034000,0.4,1.0,-1.2,0,0.6,0,0.8,-0.2,0.7,-1.5,0,0,0,1",
]


def _write(tmp_path, lines, name="g.csv"):
    path = tmp_path / name
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def _all_gesture_files():
    if not DATA.is_dir():
        pytest.skip(f"{DATA} not present")
    files = sorted(DATA.rglob("*.csv"))
    if not files:
        pytest.skip(f"no CSV files under {DATA}")
    return files


def test_all_vive_gestures_load():
    files = _all_gesture_files()
    right_is_c0 = 0
    for f in files:
        d = read_csv(f)
        assert d.names == ["c0", "c1"], f
        assert d.source == str(f)
        assert d.device == "vive-controller"
        assert all(len(tr) > 100 for tr in d.tracks), f
        assert 88.5 <= d.rate <= 90.5, (f, d.rate)
        assert d.t[0] == 0 and (np.diff(d.t) > 0).all()
        for tr in d.tracks:
            ok = tr.valid
            np.testing.assert_allclose(np.linalg.norm(tr.q[ok], axis=1), 1.0, atol=1e-9)
        # c0 is the right hand: in our frame (+x left) it sits at smaller x than c1
        right_is_c0 += d.tracks[0].p[:10, 0].mean() < d.tracks[1].p[:10, 0].mean()
    assert np.median([read_csv(f).rate for f in files[:20]]) == pytest.approx(89.5, abs=0.3)
    assert right_is_c0 > 0.9 * len(files)


def test_default_layout_and_unity_conversion(tmp_path):
    d = read_csv(_write(tmp_path, [HEAD] + ROWS))
    c0, c1 = d.tracks
    np.testing.assert_allclose(c0.t, [0, 0.011, 0.022, 0.034])
    np.testing.assert_allclose(c0.p[0], [-0.1, 0.7, -1.5])  # unity x right -> ours x left
    np.testing.assert_allclose(c0.q[3], [0, -0.6, 0, 0.8])  # (qx, -qy, -qz, qw)
    np.testing.assert_array_equal(c1.valid, [True, True, False, True])  # NaN marks lost tracking
    assert np.isnan(c1.p[2]).all() and np.isnan(c1.q[2]).all()
    assert d.rate == pytest.approx(round(1 / 0.011, 1))


def test_convention_doodle_keeps_values(tmp_path):
    d = read_csv(_write(tmp_path, [HEAD] + ROWS), convention="doodle")
    np.testing.assert_allclose(d.tracks[0].p[0], [0.1, 0.7, -1.5])


def test_time_column_names_and_extra_columns(tmp_path):
    head = HEAD.replace("t,", "Timestamp,") + ",label"
    d = read_csv(_write(tmp_path, [head] + [r + ",x" for r in ROWS]))
    assert d.names == ["c0", "c1"] and len(d.t) == 4


def test_no_time_column_needs_rate(tmp_path):
    head = HEAD.split(",", 1)[1]
    rows = [r.split(",", 1)[1] for r in ROWS]
    path = _write(tmp_path, [head] + rows)
    with pytest.raises(DoodleError, match="time") as err:
        read_csv(path)
    assert path.name in str(err.value)
    d = read_csv(path, rate=50)
    np.testing.assert_allclose(d.t, [0, 0.02, 0.04, 0.06])
    assert d.rate == 50


def test_column_map_with_names(tmp_path):
    lines = ["time,x,y,z,a,b,c,w"] + [
        "0.0,1,2,3,0,0,0,1",
        "0.5,1,2,3,0,0,0,1",
        "1.0,1,2,3,0,0,0,1",
    ]
    cmap = parse_column_map("t=time,hand.px=x,hand.py=y,hand.pz=z,hand.qx=a,hand.qy=b,hand.qz=c,hand.qw=w")
    d = read_csv(_write(tmp_path, lines), convention="openvr", columns=cmap)
    assert d.names == ["hand"] and d.rate == 2.0
    np.testing.assert_allclose(d.tracks[0].p[0], [-1, 2, -3])


def test_headerless_needs_column_map(tmp_path):
    path = _write(tmp_path, [",".join(r.split(",")[:8]) for r in ROWS])
    with pytest.raises(DoodleError, match="header") as err:
        read_csv(path)
    assert path.name in str(err.value)
    cmap = parse_column_map("t=0,c0.px=1,c0.py=2,c0.pz=3,c0.qx=4,c0.qy=5,c0.qz=6,c0.qw=7")
    d = read_csv(path, columns=cmap)
    assert d.names == ["c0"] and len(d.t) == 4
    with pytest.raises(DoodleError, match="index"):
        read_csv(path, columns={**cmap, "c0.px": "x"})
    with pytest.raises(DoodleError, match="out of range"):
        read_csv(path, columns={**cmap, "c0.px": 9})


@pytest.mark.parametrize(
    "text",
    ["t=time,c0.px", "t=", "c0.pos=x", "c0.px=x,c0.px=y", "", "bad name.px=x"],
)
def test_malformed_column_map(text):
    with pytest.raises(DoodleError):
        parse_column_map(text)


def test_incomplete_column_map(tmp_path):
    path = _write(tmp_path, [HEAD] + ROWS)
    with pytest.raises(DoodleError, match="c0.qw"):
        read_csv(path, columns={"t": "t", "c0.px": "c0_px", "c0.py": "c0_py", "c0.pz": "c0_pz",
                                "c0.qx": "c0_qx", "c0.qy": "c0_qy", "c0.qz": "c0_qz"})
    with pytest.raises(DoodleError, match="nope"):
        read_csv(path, columns=parse_column_map("t=nope,c0.px=c0_px,c0.py=c0_py,c0.pz=c0_pz,"
                                                "c0.qx=c0_qx,c0.qy=c0_qy,c0.qz=c0_qz,c0.qw=c0_qw"))


def test_prefix_missing_a_column(tmp_path):
    head = HEAD.replace(",c1_qz", ",c1_qzz")
    path = _write(tmp_path, [head] + ROWS)
    with pytest.raises(DoodleError) as err:
        read_csv(path)
    assert path.name in str(err.value) and "c1_qz" in str(err.value)


def _with(i, old, new):
    rows = list(ROWS)
    assert old in rows[i]
    rows[i] = rows[i].replace(old, new, 1)
    return rows


ROW_ERRORS = [
    # (rows, line of the error, words)
    (_with(1, "0.2,0.8", "0.2x,0.8"), 3, "column c0_px"),
    (_with(1, "0.2,0.8", "inf,0.8"), 3, "column c0_px"),
    (_with(2, "0.3,", ""), 4, "fields"),
    (_with(3, "0,0.6,0,0.8", "0,0,0,0"), 5, "track c0: zero quaternion"),
    (_with(3, "0,0.6,0,0.8", "0,0.6,0,0.5"), 5, "track c0"),
    (_with(2, "0.022000", "0.011000"), 4, "0.011000"),
    (_with(2, "0.022000", "0.001"), 4, "0.001000"),
    (_with(2, "0.022000", "nan"), 4, "time"),
]


@pytest.mark.parametrize("rows,line,words", ROW_ERRORS)
def test_row_errors(tmp_path, rows, line, words):
    path = _write(tmp_path, [HEAD] + rows)
    with pytest.raises(DoodleError) as err:
        read_csv(path)
    msg = str(err.value)
    assert f"{path.name}:{line}" in msg, msg
    assert words in msg, msg


def test_line_numbers_count_blank_lines(tmp_path):
    path = _write(tmp_path, ["", HEAD] + ROWS[:2] + [""] + _with(2, "0.3,", "zz,")[2:])
    with pytest.raises(DoodleError, match=rf"{path.name}:6: column c0_px"):
        read_csv(path)


@pytest.mark.parametrize("rows,words", [([], "no samples"), (ROWS[:1], "at least two samples")])
def test_too_few_rows(tmp_path, rows, words):
    path = _write(tmp_path, [HEAD] + rows)
    with pytest.raises(DoodleError, match=words) as err:
        read_csv(path)
    assert path.name in str(err.value)


def test_unknown_convention(tmp_path):
    with pytest.raises(DoodleError, match="unity"):
        read_csv(_write(tmp_path, [HEAD] + ROWS), convention="blender")
