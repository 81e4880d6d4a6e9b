"""Every parser a user can hand a file to, fuzzed: each input either loads or raises
DoodleError with a one-line message naming the file (or, for an expression, the column) —
no other exception, and no numpy RuntimeWarning (overflow, invalid value) on the way.

Inputs are valid files mutated (bytes flipped, cut short, junk lines inserted, numbers
replaced by nan, inf, 1e308, -0, huge integers, non-ASCII text) and random bytes; for the
``.npz`` files also valid archives with an array or header entry changed. Examples are
derandomised (tests/conftest.py): the same cases on every run.
"""

from __future__ import annotations

import io
import json
import os
import re
import warnings
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, currently_in_test_context, event, given, settings
from hypothesis import strategies as st

from doodle.core.errors import DoodleError

ROOT = Path(__file__).resolve().parents[1]
SCALE = float(os.environ.get("FUZZ_SCALE", "1"))  # e.g. FUZZ_SCALE=20 for a deeper search, once
FUZZ = settings(max_examples=int(300 * SCALE), deadline=None, suppress_health_check=list(HealthCheck))
SLOW = settings(FUZZ, max_examples=int(150 * SCALE))  # parsers whose cases take milliseconds each

SPECIALS = ["nan", "NaN", "-nan", "inf", "-inf", "Infinity", "1e308", "-1e308", "1.7976931348623157e308", "1e400",
            "5e-324", "-0", "-0.0", "0", "1", "-1", "99999999999999999999999999", "-99999999999999999999999", "1e9",
            "", " ", "+", "-", ".", "e5", "0x10", "1_000", "１", "٣", "½", "é", "nul\x00", "1,2", "\"1\""]
JUNK = ["", " ", "\t", "#", "# doodle 1", "# track c0", "# rate 0", ",,,,,,,,", "\x00\x01\x02", "é€😀\u202e",
        "\ufeff", "\r", "t,c0.ok", "[library]", "[[actions]]", 'name = "x"', "expression = \"(\"", "{", "}", "]",
        "ROOT x", "JOINT j", "End Site", "MOTION", "Frames: 100000000000", "Frame Time: 0", "CHANNELS 6",
        "OFFSET 1e308 0 0", "v 1 2", "v 1e308 1e308 1e308", "f 1 2 3", "f 1 2 99999", "f -1 -2 -3", "vt 0 0",
        "o x", "1e308,1e308,1e308", "nan,nan,nan", "0,1,2,3,4,5,6,7,8"]
NUMBER = re.compile(rb"-?\d+(?:\.\d+)?(?:[eE][-+]?\d+)?")


@st.composite
def mutated(draw, base: bytes) -> bytes:
    """``base`` with one to four mutations: mostly a number replaced (by nan, inf, 1e308…),
    else a byte changed, the file cut short, a line inserted, dropped or doubled, or bytes
    inserted — most of them text, so that not every case stops at a UTF-8 error. Places are
    drawn uniformly (hypothesis' own integers favour the start of the file)."""
    data = bytearray(base)
    where = draw(st.randoms(use_true_random=True))
    for _ in range(draw(st.integers(1, 4))):
        op = draw(st.sampled_from(["flip", "cut", "line", "number", "number", "number", "drop", "twice", "bytes"]))
        lines = bytes(data).split(b"\n")
        if op == "flip" and data:
            data[where.randrange(len(data))] = draw(st.sampled_from(b"0123456789,.-+eEn \t\r#") | st.integers(0, 255))
        elif op == "cut" and data:
            del data[where.randrange(len(data)):]
        elif op == "line":
            k = where.randrange(len(lines) + 1)
            junk = draw(st.sampled_from(JUNK) | st.text(max_size=30))
            data = bytearray(b"\n".join(lines[:k] + [junk.encode("utf-8", "surrogatepass")] + lines[k:]))
        elif op == "number":
            found = list(NUMBER.finditer(data))
            if found:  # a third of the time among the first few: headers, counts, first rows
                m = found[where.randrange(min(len(found), draw(st.sampled_from([12, len(found), len(found)]))))]
                data[m.start():m.end()] = draw(st.sampled_from(SPECIALS)).encode()
        elif op in ("drop", "twice") and len(lines) > 1:
            k = where.randrange(len(lines))
            lines[k:k + 1] = [] if op == "drop" else [lines[k], lines[k]]
            data = bytearray(b"\n".join(lines))
        elif op == "bytes":
            k = where.randrange(len(data) + 1)
            data[k:k] = draw(st.text(min_size=1, max_size=20).map(str.encode) | st.binary(min_size=1, max_size=20))
    return bytes(data)


def inputs(base: bytes):
    """Mutations of ``base`` mostly, random bytes sometimes."""
    return st.one_of(mutated(base), mutated(base), mutated(base), st.binary(max_size=600))


def note(what: str) -> None:
    """Count outcomes in hypothesis' statistics (``--hypothesis-show-statistics``)."""
    if currently_in_test_context():
        event(what)


def check(load, path: Path, data: bytes | None = None, places: tuple = ()):
    """Load ``path`` (written with ``data`` first): DoodleError naming the file (or one of
    ``places``, the other files it names) or success, no other exception and no RuntimeWarning.
    Returns what loaded, or None."""
    if data is not None:
        path.write_bytes(data)
    places = (path.name, *places)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            out = load(path)
            note("loaded")
        except DoodleError as exc:
            message = str(exc)
            assert any(place in message for place in places), message
            assert "\n" not in message and "Traceback" not in message, message
            note("refused (DoodleError)")
            out = None
    numeric = [w for w in caught if issubclass(w.category, RuntimeWarning)]
    assert not numeric, [str(w.message) for w in numeric]
    for w in caught:  # the only warnings: located ones for the user (no ResourceWarning either)
        assert w.category is UserWarning and path.name in str(w.message), (w.category, str(w.message))
    if caught:
        note("with a located warning")
    return out


@pytest.fixture(scope="module")
def work(tmp_path_factory):
    return tmp_path_factory.mktemp("fuzz")


# --------------------------------------------------------------------------- doodle files and CSV


def _motion(n: int = 40, tracks: int = 2):
    """A plausible short recording: hands moving a few centimetres per sample."""
    t = np.arange(n) / 90.0
    out = []
    for k in range(tracks):
        p = np.column_stack([0.2 * np.sin(3 * t + k), 1.0 + 0.1 * np.cos(2 * t), 0.3 * t])
        a = 0.5 * t + k
        q = np.column_stack([np.zeros(n), np.sin(a / 2), np.zeros(n), np.cos(a / 2)])
        out.append((p, q))
    return t, out


def _doodle_text() -> bytes:
    t, tracks = _motion()
    head = ["# doodle 1", "# device vive-controller", "# rate 90", "# units m", "# convention openvr",
            "# track c0 role=right_hand serial=LHR-1", "# track c1", "# x-note fuzzed",
            "t," + ",".join(f"c{k}.{f}" for k in range(2) for f in ("ok", "px", "py", "pz", "qx", "qy", "qz", "qw"))]
    rows = []
    for i in range(len(t)):
        cells = [f"{t[i]:.6f}"]
        for k, (p, q) in enumerate(tracks):
            ok = not (k == 1 and 10 <= i < 13)
            cells += ["1" if ok else "0"] + ([f"{v:.6f}" for v in (*p[i], *q[i])] if ok else ["nan"] * 7)
        rows.append(",".join(cells))
    return ("\n".join(head + rows) + "\n").encode()


def _csv_text() -> bytes:
    t, tracks = _motion()
    head = "t," + ",".join(f"c{k}_{f}" for k in range(2) for f in ("px", "py", "pz", "qx", "qy", "qz", "qw"))
    rows = [",".join([f"{t[i]:.6f}"] + [f"{v:.6f}" for p, q in tracks for v in (*p[i], *q[i])])
            for i in range(len(t))]
    return ("\n".join([head] + rows) + "\n").encode()


def _load_and_tokenize(path):
    """A loaded doodle must also tokenise: what loads is fit for the Segmenter."""
    from doodle.input.loader import load
    from doodle.input.segmenter import tokenize_doodle

    doodle = load(path, convention="unity" if path.suffix == ".csv" else None)
    tokenize_doodle(doodle)
    return doodle


def test_the_bases_load(work):
    for name, data in (("base.doodle", _doodle_text()), ("base.csv", _csv_text())):
        doodle = check(_load_and_tokenize, work / name, data)
        assert doodle is not None and len(doodle.tracks) == 2, name


@FUZZ
@given(data=inputs(_doodle_text()))
def test_fuzz_doodle_files(work, data):
    check(_load_and_tokenize, work / "fuzz.doodle", data)


@FUZZ
@given(data=inputs(_csv_text()))
def test_fuzz_csv_files(work, data):
    check(_load_and_tokenize, work / "fuzz.csv", data)


@FUZZ
@given(text=st.text(max_size=80) | st.sampled_from(["t=0,c0.px=1,c0.py=2,c0.pz=3,c0.qx=4,c0.qy=5,c0.qz=6,c0.qw=7",
                                                     "t=time,c0.px=x", "=", ",,", "c0.px=1,c0.px=2"]))
def test_fuzz_column_maps(text):
    from doodle.input.csvimport import parse_column_map

    try:
        parse_column_map(text)
    except DoodleError as exc:
        assert str(exc).startswith("column map") and "\n" not in str(exc)


# --------------------------------------------------------------------------- BVH


def _bvh_text() -> bytes:
    from retarget.bvh import format_bvh, read_bvh

    motion = read_bvh(ROOT / "library" / "builtin" / "clips" / "greet.bvh")
    small = type(motion)(motion.skeleton, motion.translations[:4], motion.rotations[:4], motion.frame_time)
    return "".join(format_bvh(small)).encode()


@FUZZ
@given(data=inputs(_bvh_text()))
def test_fuzz_bvh_files(work, data):
    from retarget.bvh import read_bvh

    check(read_bvh, work / "fuzz.bvh", data)


# --------------------------------------------------------------------------- library TOML and expressions


LIBRARY = b'''[library]
name = "fuzzed"
format = 1
states = ["down"]

[skeleton]
right_hand = "RightHand"

[[actions]]
name = "Wave"
expression = "(T_X T_N_X)+ T_Y?"
in_place = true
tolerance = 3
shape = "wave.npz"
track = "c0"
clips = ["wave.bvh"]
stages = [1, 2, 3, 4]
cycle_length = 0.5

[[actions]]
name = "Sit"
expression = "T_N_Y (R_X | R_N_X)*"
sets = ["down"]

[[actions]]
name = "Stand"
expression = "T_Y R_Y"
clears = ["down"]
requires = ["down"]

[[interactions]]
name = "Greeting"
actions = ["Wave", "Sit"]
constraints = ["D(0, 1, Personal)"]
contact = ["right_hand", "head"]
placement = [0, 0.6, 180]
'''


def _load_and_compile(path):
    from grammar.library import compile_library
    from library.manifest import load_library

    return compile_library(load_library(path))


def test_the_library_base_compiles(work):
    from grammar.shapes import POINTS, save_paths

    save_paths(work / "wave.npz", np.cumsum(np.full((2, POINTS, 3), 0.01), axis=1))
    assert check(_load_and_compile, work / "library.toml", LIBRARY) is not None


@SLOW
@given(data=inputs(LIBRARY))
def test_fuzz_library_manifests(work, data):
    from grammar.shapes import POINTS, save_paths

    if not (work / "wave.npz").exists():
        save_paths(work / "wave.npz", np.cumsum(np.full((2, POINTS, 3), 0.01), axis=1))
    check(_load_and_compile, work / "library.toml", data, places=(".npz (shape of action",))


def _expressions() -> list[str]:
    text = (ROOT / "library" / "builtin" / "library.toml").read_text()
    return re.findall(r'^expression = "(.*)"$', text, re.M)


@FUZZ
@given(text=st.sampled_from(_expressions()).flatmap(lambda e: mutated(e.encode())).map(
    lambda b: b.decode("utf-8", "replace")) | st.text(alphabet="T_XYZNR ()|*+?", max_size=40) | st.text(max_size=40))
def test_fuzz_expressions(text):
    from grammar.automata import compile_expression
    from grammar.expr import parse

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        try:
            compile_expression(parse(text, "Fuzz"))
        except DoodleError as exc:
            message = str(exc)
            assert "action 'Fuzz'" in message and "\n" not in message, message
            assert "column" in message or "empty" in message or "expression" in message, message


# --------------------------------------------------------------------------- edits JSON


EDITS = b'{"time": 0.5, "weight": -0.25, "segments": [{"track": "c0", "index": 2, "time": 1.0, "weight": -0.5}, ' \
        b'{"track": "c1", "time": 0}]}\n'


@FUZZ
@given(data=inputs(EDITS))
def test_fuzz_edits_files(work, data):
    from doodle.app.pipeline import read_edits

    check(read_edits, work / "edits.json", data)


# --------------------------------------------------------------------------- .npz files


def _npz(arrays: dict) -> bytes:
    buf = io.BytesIO()
    np.savez(buf, **arrays)
    return buf.getvalue()


VALUES = [np.nan, np.inf, -np.inf, 1e308, -1e308, -1.0, 0.0, -0.0, 5e-324, 1e9, 2 ** 62]


@st.composite
def changed_arrays(draw, arrays: dict) -> bytes:
    """``arrays`` with one to three arrays changed: a value, the shape, the dtype, or gone —
    or, for a JSON header, an entry of it — saved as a new archive."""
    arrays = dict(arrays)
    for _ in range(draw(st.integers(1, 3))):
        key = draw(st.sampled_from(sorted(arrays) + ["extra"]))
        a = arrays.get(key, np.zeros(3))
        op = draw(st.sampled_from(["value", "value", "shape", "dtype", "drop", "json"]))
        if op == "json" and a.dtype.kind == "U" and a.shape == () and str(a).startswith("{"):
            meta = json.loads(str(a))
            field = draw(st.sampled_from(sorted(meta)))
            meta[field] = draw(st.sampled_from([None, -1, 0, 1e308, "x", [], {}, [1, "a"], True, 7, 0.5, 1e-9]))
            arrays[key] = np.array(json.dumps(meta))
        elif op == "value" and a.size and a.dtype.kind in "fiu":
            a = a.astype(float).copy()
            a.flat[draw(st.integers(0, a.size - 1))] = draw(st.sampled_from(VALUES))
            arrays[key] = a
        elif op == "shape":
            flat = a.reshape(-1)
            arrays[key] = draw(st.sampled_from([flat, flat[:1], flat[:0], np.stack([a, a]), a.T, flat.reshape(-1, 1)]))
        elif op == "dtype":
            arrays[key] = draw(st.sampled_from([a.astype(str), a.astype(bool), np.zeros(a.shape, complex),
                                                np.zeros(a.shape, "M8[s]") if a.ndim else np.array("x")]))
        elif op == "drop":
            arrays.pop(key, None)
    return _npz(arrays)


def npz_inputs(arrays: dict):
    base = _npz(arrays)
    return st.one_of(changed_arrays(arrays), changed_arrays(arrays), mutated(base), st.binary(max_size=600),
                     st.sampled_from([_npz({"x": np.array([{"a": 1}], dtype=object)}), b"PK\x05\x06" + b"\0" * 18,
                                      np.lib.format.magic(1, 0) + b"junk"]))


HEADER_ALPHABET = "0123456789 ,()'\"<>|=:{}\n\t\\_-+.xLeflsTruFadiUbMcSO[]\x00é"


@st.composite
def npy_headers(draw) -> bytes:
    """The header of a saved array (format 1.0 or 2.0), its text mutated with the characters
    a header is made of."""
    shape = tuple(draw(st.lists(st.integers(0, 12), max_size=4)))
    dtype = draw(st.sampled_from(["<f8", ">i4", "|b1", "<U7", "|S3", "<c16", "M8[s]", [("a", "<f8")]]))
    buf = io.BytesIO()
    np.lib.format.write_array(buf, np.zeros(shape, dtype), version=draw(st.sampled_from([(1, 0), (2, 0)])))
    data = bytearray(buf.getvalue())
    end = data.index(b"\n") + 1
    for _ in range(draw(st.integers(0, 4))):
        at = draw(st.integers(10, end - 1))
        data[at:at + draw(st.integers(0, 3))] = draw(st.text(HEADER_ALPHABET, max_size=3)).encode("latin1", "replace")
    return bytes(data)


@FUZZ
@given(data=npy_headers())
def test_the_plain_header_reader_reads_as_numpy_does(data):
    """doodle.core.npz reads the header numpy writes by a regular expression: whatever it
    reads, numpy's parser reads the same; what it does not, numpy's parser gets."""
    from doodle.core.npz import _plain_header

    version, rest = tuple(data[6:8]), io.BytesIO(data[8:])
    plain = _plain_header(io.BytesIO(data[8:]), version)
    read = np.lib.format.read_array_header_1_0 if version == (1, 0) else np.lib.format.read_array_header_2_0
    try:
        theirs = read(rest)
    except Exception:  # noqa: BLE001 - anything numpy's parser refuses (tokenize errors among them)
        theirs = None
    if plain is not None:
        assert plain == theirs and all(type(n) is int for n in plain[0]) and type(plain[1]) is bool
    event("read by the expression" if plain is not None else "left to numpy")


def _model_arrays() -> dict:
    from laban.models import DEFAULT

    with np.load(DEFAULT, allow_pickle=False) as z:
        return {k: z[k] for k in z.files}


def _load_and_score(path):
    """A loaded model must also score a curve, without warnings."""
    from laban.classify import quality
    from laban.models import load

    model = load(path)
    t = np.linspace(0, 1, 60)
    p = np.column_stack([np.sin(4 * t), 0.3 * t, np.cos(3 * t)]) * 0.3
    q = np.column_stack([np.zeros(60), np.sin(t / 2), np.zeros(60), np.cos(t / 2)])
    quality(model, t, p, q)
    return model


@SLOW
@given(data=npz_inputs(_model_arrays()))
def test_fuzz_effort_models(work, data):
    check(_load_and_score, work / "model.npz", data)


@FUZZ
@given(data=npz_inputs({"paths": np.cumsum(np.full((2, 32, 3), 0.01), axis=1), "format": np.array(1)}))
def test_fuzz_shape_files(work, data):
    from grammar.shapes import load_paths, shape_set

    def load(path):
        paths = load_paths(path, "Wave")
        shape_set({"Wave": paths}, {"Wave": "T_X+"})
        return paths

    check(load, work / "shape.npz", data)


def _terrain(spec_of):
    def load(path):
        from retarget.terrain import parse_terrain

        ground = parse_terrain(spec_of(path))
        ground.height(np.array([[0.1, 0.2], [5.0, -3.0], [1e3, 1e3]]))
        ground.project(np.array([[0.1, 2.0, 0.2], [0.0, -5.0, 0.0]]))
        return ground

    return load


@FUZZ
@given(data=npz_inputs({"heights": np.arange(12.0).reshape(3, 4) * 0.1, "spacing": np.array(0.5),
                        "origin": np.array([-1.0, -1.0])}))
def test_fuzz_heightfield_files(work, data):
    check(_terrain(lambda p: f"heightfield:{p}"), work / "ground.npz", data)


OBJ = b"""# a ground of two quads and a raised corner
mtllib ground.mtl
o ground
v -1 0.25 -1
v 1 0.25 -1
v 1 0.25 1
v -1 0.25 1
v 2 0.5 1
vt 0 0
vn 0 1 0
usemtl grass
s off
f 1/1/1 4/1/1 3/1/1 2/1/1
f 2//1 3//1 5//1
f -1 -2 -4
"""


@FUZZ
@given(data=inputs(OBJ))
def test_fuzz_obj_meshes(work, data):
    check(_terrain(lambda p: f"mesh:{p}"), work / "ground.obj", data)


def _ply() -> bytes:
    return (b"ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
            b"element face 2\nproperty list uchar int vertex_indices\nend_header\n"
            b"-1 0 -1\n1 0 -1\n1 0 1\n-1 0 1\n3 0 3 2\n3 0 2 1\n")


@SLOW
@given(data=inputs(_ply()))
def test_fuzz_ply_meshes(work, data):
    check(_terrain(lambda p: f"mesh:{p}"), work / "ground.ply", data)


@FUZZ
@given(spec=st.text(max_size=30) | st.sampled_from(["flat:nan", "flat:1e308", "jacksboro:0", "jacksboro:1e308",
                                                   "s1045:-1", "heightfield:", "mesh:", "flat:", "FLAT:2"]))
def test_fuzz_terrain_specs(spec):
    from retarget.terrain import parse_terrain

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        try:
            parse_terrain(spec)
        except DoodleError as exc:
            assert "terrain" in str(exc) and "\n" not in str(exc), str(exc)


# --------------------------------------------------------------------------- calibration and mapping TOML


CALIBRATION = b"""# written by `doodle calibrate`
[segmenter]
eps = 0.05
theta = 0.3
smoothing = "savgol"

[mount]
c0 = [0.0, 0.0, 0.0, 1.0]
c1 = [0.0, 0.7071068, 0.0, 0.7071068]
"""


@FUZZ
@given(data=inputs(CALIBRATION))
def test_fuzz_calibration_files(work, data):
    from doodle.input.settings import read_calibration

    check(read_calibration, work / "cal.toml", data)


MAPPING = b"""[[map]]
match = "*punch*"
action = "Punch"
expression = "T_N_Z T_Z"
cyclic = false

[[map]]
match = "walk_*.bvh"
action = "Walk"
"""


@FUZZ
@given(data=inputs(MAPPING))
def test_fuzz_import_maps(work, data):
    from retarget.importer import read_map

    check(read_map, work / "map.toml", data)
