"""The Segmenter: token alphabet, recognition of strokes, invariances, streaming = batch."""

from dataclasses import replace

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from doodle.core.errors import DoodleError
from doodle.core.model import Track
from doodle.input.segmenter import Segmenter, SegmenterParams, debounce, tokenize
from doodle.synth.strokes import lost_tracking, resample, stroke, synth_track
from doodle.core.tokens import ALPHABET, CODES, NAMES, T_BASE, Token, direction_index

T_TOKENS = [n for n in ALPHABET if n.startswith("T_") and n != "T_STILL"]
R_TOKENS = [n for n in ALPHABET if n.startswith("R_")]
SETTINGS = settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])


def names(tokens):
    return [k.name for k in tokens]


def stream(track: Track, rate: float, params=SegmenterParams()):
    seg = Segmenter(rate, params, track.name)
    out = []
    for i in range(len(track)):
        out += seg.push(track.t[i], track.p[i], track.q[i], bool(track.valid[i]))
    return out + seg.close()


def performed(tokens, rate=90.0, seed=0, **kw):
    """A track performing each token as one stroke, with pauses around and between."""
    strokes = [stroke("T_STILL", 0.5)]
    for name in tokens:
        strokes += [stroke(name, 0.6), stroke("T_STILL", 0.4)]
    return synth_track(strokes, rate=rate, seed=seed, **kw)[0]


# --- the alphabet -------------------------------------------------------------------------

def test_alphabet_has_26_bins_per_kind_and_still():
    assert len(T_TOKENS) == 26 and len(R_TOKENS) == 26 and "T_STILL" in ALPHABET
    for name in ("T_Z", "T_N_Z", "T_X_Y_Z", "T_N_X_Y", "T_X_N_Y", "T_Y_N_Z", "T_N_X_N_Y_N_Z", "R_Y", "R_N_X_Z"):
        assert name in CODES


@pytest.mark.parametrize(
    "vector, name",
    [((0, 0, 1), "T_Z"), ((0, 0, -1), "T_N_Z"), ((1, 0, 0), "T_X"), ((-1, 1, 0), "T_N_X_Y"),
     ((1, 1, 1), "T_X_Y_Z"), ((0.3, 1, 0), "T_Y"), ((0.6, 1, 0), "T_X_Y"), ((1, -1, -1), "T_X_N_Y_N_Z")],
)
def test_direction_bins(vector, name):
    """An axis counts when the direction is within 60° of it (|cos| ≥ 0.5)."""
    assert NAMES[T_BASE + direction_index(*map(float, vector))] == name


def test_debounce_absorbs_short_excursions_and_partitions_samples():
    z, y, s = CODES["T_Z"], CODES["T_Y"], CODES["T_STILL"]
    codes = np.array([s] * 3 + [z] * 6 + [y] * 2 + [z] * 5 + [y] * 7)
    tokens = debounce(codes, alpha=5)
    assert tokens == [Token("T_Z", 0, 16), Token("T_Y", 16, 23)]
    assert debounce(np.array([z] * 4), alpha=5) == []


# --- recognition of strokes ---------------------------------------------------------------

@pytest.mark.parametrize("name", T_TOKENS + R_TOKENS)
def test_every_direction_is_recognised(name):
    """Each of the 52 directions, performed as one stroke, gives exactly its token."""
    track = performed([name], seed=CODES[name])
    tokens = tokenize(track, 90.0)
    assert names(tokens) == ["T_STILL", name, "T_STILL"]


def test_tokens_carry_sample_ranges_covering_the_strokes():
    strokes = [stroke("T_STILL", 0.5), stroke("T_Z", 0.8), stroke("T_STILL", 0.5), stroke("R_Y", 0.8),
               stroke("T_STILL", 0.5)]
    track, ranges = synth_track(strokes, rate=90.0, seed=3)
    tokens = tokenize(track, 90.0)
    assert names(tokens) == ["T_STILL", "T_Z", "T_STILL", "R_Y", "T_STILL"]
    assert tokens[0].start == 0 and tokens[-1].end == len(track)
    assert all(a.end == b.start for a, b in zip(tokens, tokens[1:]))
    for token, (start, end) in zip(tokens[1::2], ranges[1::2]):  # the moving strokes
        overlap = min(token.end, end) - max(token.start, start)
        assert overlap > 0.6 * (end - start)


def test_figurine_turned_in_the_world_still_walks_forward():
    """Moving along its own front after a turn: T_Z whatever the world direction."""
    track = synth_track([stroke("T_STILL", 0.4), stroke("R_Y", 0.8, 2.0), stroke("T_STILL", 0.4),
                         stroke("T_Z", 0.8), stroke("T_STILL", 0.4)], seed=4)[0]
    assert names(tokenize(track, 90.0)) == ["T_STILL", "R_Y", "T_STILL", "T_Z", "T_STILL"]


# --- invariances (property tests) ---------------------------------------------------------

moves = st.sampled_from(T_TOKENS + R_TOKENS)
doodles = st.tuples(st.lists(moves, min_size=1, max_size=5), st.integers(0, 2**16))


def transformed(track: Track, rotation: Rotation, offset, scale=1.0) -> Track:
    p = rotation.apply(track.p) * scale + offset
    q = (rotation * Rotation.from_quat(track.q)).as_quat()
    return replace(track, p=p, q=q)


@SETTINGS
@given(doodles, st.integers(0, 2**16), st.floats(-50, 50))
def test_rigid_motion_leaves_tokens_unchanged(doodle, rseed, shift):
    """Translating the whole doodle and turning it about the vertical changes no token (the
    prop's up is read from gravity at rest, so only turns about the vertical are free)."""
    track = performed(doodle[0], seed=doodle[1])
    rotation = Rotation.from_rotvec([0.0, np.random.default_rng(rseed).uniform(-np.pi, np.pi), 0.0])
    moved = transformed(track, rotation, np.array([shift, -0.5 * shift, 2.0]))
    assert tokenize(moved, 90.0) == tokenize(track, 90.0)


@SETTINGS
@given(doodles, st.floats(0.1, 20))
def test_scaling_with_the_thresholds_leaves_tokens_unchanged(doodle, s):
    """A doodle scaled by s, read with thresholds scaled by s (a bigger prop, calibrated), is
    the same doodle: identical tokens and ranges."""
    track = performed(doodle[0], seed=doodle[1])
    big = transformed(track, Rotation.identity(), 0.0, s)
    assert tokenize(big, 90.0, SegmenterParams().scaled(s)) == tokenize(track, 90.0)


@pytest.mark.parametrize("s", [0.6, 1.5, 2.5])
def test_amplitude_does_not_change_the_token_string(s):
    """With fixed default thresholds, strokes performed smaller or larger read the same:
    only the boundaries with stillness move."""
    tokens = ["T_Z", "T_X", "T_N_Y", "R_Y", "T_N_X_Z", "R_N_Z"]
    base = names(tokenize(performed(tokens, seed=9), 90.0))
    assert names(tokenize(performed(tokens, seed=9, scale=s), 90.0)) == base


@pytest.mark.parametrize("rate", [144.0, 120.0, 60.0])
def test_resampled_doodle_gives_the_same_tokens_with_alpha_scaled(rate):
    track = performed(["T_Z", "T_N_X_Y", "R_Y", "T_N_Z", "R_N_X"], seed=11)
    other = resample(track, rate)
    assert SegmenterParams().alpha(90.0) == 5
    assert SegmenterParams().alpha(rate) == round(5 * rate / 90)
    a, b = tokenize(track, 90.0), tokenize(other, rate)
    assert names(a) == names(b)
    for x, y in zip(a[1:], b[1:]):  # boundaries agree within a few hundredths of a second
        assert abs(track.t[x.start] - other.t[y.start]) < 0.05


# --- streaming equals batch ---------------------------------------------------------------

@SETTINGS
@given(doodles, st.sampled_from([60.0, 90.0, 144.0]), st.booleans(), st.booleans())
def test_streaming_equals_batch_on_generated_doodles(doodle, rate, savgol, lost):
    track = performed(doodle[0], rate=rate, seed=doodle[1])
    if lost:
        mid = track.t[-1] / 2
        track = lost_tracking(track, mid, mid + 0.2)
    params = SegmenterParams(smoothing="savgol" if savgol else "laplacian")
    assert stream(track, rate, params) == tokenize(track, rate, params)


@SETTINGS
@given(st.integers(2, 400), st.integers(0, 2**16), st.floats(1e-4, 1.0))
def test_streaming_equals_batch_on_random_walks(n, seed, step):
    """Pure noise: random positions and orientations, any length from two samples."""
    rng = np.random.default_rng(seed)
    t = np.cumsum(rng.uniform(0.2, 1.8, n)) / 90.0
    p = np.cumsum(rng.normal(scale=step, size=(n, 3)), axis=0)
    q = (Rotation.from_rotvec(np.cumsum(rng.normal(scale=step, size=(n, 3)), axis=0))).as_quat()
    track = Track("c0", t - t[0], p, q, np.ones(n, bool))
    assert stream(track, 90.0) == tokenize(track, 90.0)


def test_streaming_equals_batch_on_real_recordings(vive_files):
    from doodle.input.csvimport import read_csv

    for path in vive_files[::25]:
        doodle = read_csv(path, convention="unity")
        for track in doodle.tracks:
            assert stream(track, doodle.rate) == tokenize(track, doodle.rate), path


def test_pending_token_gives_live_feedback():
    track = performed(["T_Z"], seed=2)
    seg = Segmenter(90.0)
    seen = set()
    for i in range(len(track)):
        seg.push(track.t[i], track.p[i], track.q[i])
        if seg.pending:
            seen.add(seg.pending.name)
    assert "T_Z" in seen


# --- lost tracking and bad input ----------------------------------------------------------

def test_short_lost_tracking_is_repaired():
    track = performed(["T_Z", "T_X"], seed=5)
    gap = lost_tracking(track, 1.0, 1.2)  # inside the T_Z stroke
    assert not gap.valid.all()
    assert names(tokenize(gap, 90.0)) == names(tokenize(track, 90.0))


def test_lost_tracking_at_the_ends_reads_as_still():
    track = performed(["T_Z"], seed=6)
    cut = lost_tracking(lost_tracking(track, 0.0, 0.3), track.t[-1] - 0.3, track.t[-1])
    assert names(tokenize(cut, 90.0)) == ["T_STILL", "T_Z", "T_STILL"]
    assert stream(cut, 90.0) == tokenize(cut, 90.0)


def test_long_lost_tracking_is_a_named_error():
    track = lost_tracking(performed(["T_Z", "T_X"], seed=5), 1.0, 2.0)
    with pytest.raises(DoodleError, match=r"track c0 lost tracking for 1\.\d\d s"):
        tokenize(track, 90.0)
    with pytest.raises(DoodleError, match="lost tracking"):
        stream(track, 90.0)
    assert names(tokenize(track, 90.0, SegmenterParams(max_gap=2.0)))  # the documented way out


def _broken(kind: str) -> Track:
    track = performed(["T_Z"], seed=1)
    t, p, q, valid = track.t.copy(), track.p.copy(), track.q.copy(), track.valid.copy()
    if kind == "nan":
        p[40, 1] = np.nan
    elif kind == "inf":
        q[40, 0] = np.inf
    elif kind == "duplicate time":
        t[40] = t[39]
    elif kind == "time goes back":
        t[40] = t[38]
    elif kind == "zero quaternion":
        q[40] = 0.0
    elif kind == "non-unit quaternion":
        q[40] *= 2.0
    elif kind == "never tracked":
        valid[:] = False
        p[:] = np.nan
    return Track("c0", t, p, q, valid)


@pytest.mark.parametrize("kind, message", [
    ("nan", "sample 40 .*NaN or infinite"), ("inf", "sample 40 .*NaN or infinite"),
    ("duplicate time", "sample 40: time .* does not come after"),
    ("time goes back", "sample 40: time .* does not come after"),
    ("zero quaternion", "sample 40 .*quaternion norm 0"), ("non-unit quaternion", "sample 40 .*quaternion norm 2"),
    ("never tracked", "never tracked"),
])
def test_bad_samples_are_named_errors_in_both_forms(kind, message):
    track = _broken(kind)
    with pytest.raises(DoodleError, match=message):
        tokenize(track, 90.0)
    with pytest.raises(DoodleError, match=message):
        stream(track, 90.0)


@pytest.mark.parametrize("n", [0, 1])
def test_too_few_samples(n):
    track = Track("c0", np.arange(n) / 90.0, np.zeros((n, 3)), np.tile([0, 0, 0, 1.0], (n, 1)), np.ones(n, bool))
    with pytest.raises(DoodleError, match="at least two"):
        tokenize(track, 90.0)
    with pytest.raises(DoodleError, match="at least two"):
        stream(track, 90.0)


def test_bad_parameters_are_named():
    with pytest.raises(DoodleError, match="eps"):
        SegmenterParams(eps=float("nan"))
    with pytest.raises(DoodleError, match="smoothing"):
        SegmenterParams(smoothing="gauss")


def test_a_quick_rounded_corner_keeps_its_diagonal():
    """Up, then back, rounded in one quick movement: the hand crosses the up-back diagonal in
    fewer than α samples, yet the diagonal is a token; a corner crossed in a single sample is
    not (the streaming Segmenter agrees: the streaming-equals-batch tests above)."""
    from doodle.core.tokens import CODES
    from doodle.input.segmenter import debounce

    up, diag, back = CODES["T_Y"], CODES["T_Y_N_Z"], CODES["T_N_Z"]
    codes = np.array([up] * 8 + [diag] * 3 + [back] * 8)
    assert [t.name for t in debounce(codes, 5)] == ["T_Y", "T_Y_N_Z", "T_N_Z"]
    once = np.array([up] * 8 + [diag] + [back] * 8)
    assert [t.name for t in debounce(once, 5)] == ["T_Y", "T_N_Z"]
    same_axis = np.array([up] * 8 + [CODES["T_X_Y"]] * 3 + [up] * 8)  # a wobble, not a corner
    assert [t.name for t in debounce(same_axis, 5)] == ["T_Y"]
