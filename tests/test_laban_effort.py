"""Time and Weight that describe quality, not size or sampling: the Effort features and the
shipped model's decisions under uniform scaling (×0.1–×10) and tracking rates (30–144 Hz);
the EMOTE-style procedure; calibration; the Time and Weight classifiers in model files."""

import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from doodle.core.errors import DoodleError
from laban import synth
from laban.classify import quality
from laban.factors import Logistic, temperature
from laban.features import EFFORT_NAMES, EFFORT_SOURCES, effort_features
from laban.models import load, save
from laban.procedures import emote, presented

MODEL = load()
TAKES = synth.dataset(people=1, repeats=1, seed=17, patterns=("circle", "zigzag", "thrust", "lemniscate"))


def _take(k):
    e = TAKES[k % len(TAKES)]
    return e.t, e.p, e.q


def _probabilities(t, p):
    x = effort_features(t, p)[None]
    return float(MODEL.factors["time"].probability(x)[0]), float(MODEL.factors["weight"].probability(x)[0])


def test_every_feature_has_its_source():
    assert len(EFFORT_NAMES) == len(set(EFFORT_NAMES)) >= 10
    for name in EFFORT_NAMES:
        assert len(EFFORT_SOURCES[name]) > 40, name
    for factor in ("time", "weight"):
        assert MODEL.factors[factor].coef.shape == (len(EFFORT_NAMES),)


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 10_000), st.floats(0.1, 10.0))
def test_uniform_scaling_leaves_the_features_and_the_effort_unchanged(k, s):
    t, p, q = _take(k)
    f0, f1 = effort_features(t, p), effort_features(t, s * (p - p[0]) + 3.0)
    np.testing.assert_allclose(f1, f0, rtol=1e-6, atol=1e-6)
    e0, e1 = quality(MODEL, t, p, q), quality(MODEL, t, s * (p - p[0]) + p[0], q)
    if s * np.linalg.norm(np.ptp(p, axis=0)) > 0.05:  # not a still hand at this size
        assert (e1.time, e1.weight, e1.state) == (e0.time, e0.weight, e0.state)


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 10_000), st.floats(30.0, 144.0), st.floats(0.1, 10.0))
def test_tracking_rate_and_size_leave_the_effort_unchanged(k, rate, s):
    """The same movement tracked at 30–144 Hz (jittered clock), at any size: the
    probabilities move by little, and no confident decision changes."""
    t, p, q = _take(k)
    rng = np.random.default_rng(k)
    ref = _probabilities(*presented(t, p, q, 1.0, 90.0, rng, noise=0.0)[:2])
    got = _probabilities(*presented(t, p, q, s, rate, rng, noise=0.0)[:2])
    for a, b in zip(ref, got):
        assert abs(a - b) < 0.08, (ref, got)
        if max(a, 1 - a) > 0.65:
            assert (a >= 0.5) == (b >= 0.5), (ref, got)


def test_features_are_finite_for_degenerate_segments():
    t = np.linspace(0, 1, 50)
    for p in (np.zeros((50, 3)), np.column_stack([t, t, t]), np.column_stack([t**8, 0 * t, 0 * t])):
        assert np.isfinite(effort_features(t, p)).all()
    assert np.isfinite(effort_features(t[:2], np.zeros((2, 3)))).all()


def _stroke():
    t = np.arange(0.0, 2.0, 1 / 30)
    x = 0.5 * (1 - np.cos(np.pi * np.clip(t - 0.5, 0, 1)))  # rest, one smooth stroke, rest
    return t, np.column_stack([x, 0.2 * x**2, 0 * t]), np.tile([0, 0, 0, 1.0], (len(t), 1))


def test_emote_timing_keeps_the_path_and_changes_its_timing():
    t, p, q = _stroke()
    rng = np.random.default_rng(0)
    sudden = emote(t, p, q, 1, -1, rng)
    sustained = emote(t, p, q, -1, -1, rng)
    strong = emote(t, p, q, -1, 1, rng)
    assert sudden[0][-1] < t[-1] < sustained[0][-1]
    for tt, pp, qq in (sudden, sustained, strong):
        assert np.all(np.diff(tt) > 0) and len(tt) == len(pp) == len(qq)
        np.testing.assert_allclose(pp[0], p[0], atol=1e-9)
        np.testing.assert_allclose(pp[-1], p[-1], atol=1e-6)
    assert strong[1][:, 0].max() > p[:, 0].max() + 0.01  # the overshoot past the goal
    assert strong[1][:, 0].min() < p[:, 0].min() - 0.005  # the anticipation


def test_emote_timing_never_moves_faster_than_people_do():
    """A fast neutral stroke (a 0.8 m punch in 0.3 s, 5 m/s at its peak) made Sudden Strong:
    its duration shortened no further than keeps it under the fastest real hands (12 m/s),
    where the factor alone took it to 17-23 m/s."""
    from doodle.core.profiles import FASTEST

    t = np.linspace(0.0, 0.3, 28)
    u = t / 0.3
    p = np.column_stack([0.8 * (10 * u**3 - 15 * u**4 + 6 * u**5), 0 * t, 0 * t])
    q = np.tile([0.0, 0.0, 0.0, 1.0], (len(t), 1))
    for seed in range(4):
        tt, pp, _ = emote(t, p, q, 1, 1, np.random.default_rng(seed))
        speed = np.linalg.norm(np.diff(pp, axis=0), axis=1) / np.diff(tt)
        assert speed.max() <= FASTEST * 1.02
        assert tt[-1] < t[-1]  # still Sudden: quicker than the neutral


@pytest.mark.parametrize("lw", [1, pytest.param(-1, marks=pytest.mark.xfail(
    strict=True, reason="the shipped model reads this 1 s stroke's Sudden Light rendition (0.45 s, flat-topped) "
                        "as Sustained (P(Sudden) 0.19): it judges tempo in absolute terms"))])
def test_the_shipped_model_reads_emote_sudden_as_sudden(lw):
    t, p, q = _stroke()
    p_sudden = [_probabilities(*emote(t, p, q, lt, lw, np.random.default_rng(1))[:2])[0] for lt in (1, -1)]
    assert p_sudden[0] > 0.5 > p_sudden[1] and p_sudden[0] > p_sudden[1] + 0.25, (lw, p_sudden)


def test_temperature_scaling_recovers_a_known_temperature():
    rng = np.random.default_rng(3)
    logits = rng.normal(0, 3, 20000)
    y = np.where(rng.random(len(logits)) < 1 / (1 + np.exp(-logits / 2.0)), 1, -1)
    assert temperature(logits, y) == pytest.approx(2.0, rel=0.05)


def test_abstains_when_unsure():
    t, p, q = _take(0)
    unsure = Logistic(np.zeros(len(EFFORT_NAMES)), np.ones(len(EFFORT_NAMES)), np.zeros(len(EFFORT_NAMES)), 0.1)
    from dataclasses import replace

    e = quality(replace(MODEL, factors={"time": unsure, "weight": unsure}), t, p, q)
    assert e.time == e.weight == 0.0 and 0.5 < e.p_sudden < 0.6 and e.state


def test_model_files_check_the_time_and_weight_classifiers(tmp_path):
    path = save(MODEL, tmp_path / "m.npz")
    data = dict(np.load(path, allow_pickle=False))
    for key, value, said in (("factor_time_coef", np.zeros(3), "must be numbers shaped"),
                             ("factor_weight_temperature", np.array(0.0), "'factor_weight_temperature' holds 0"),
                             ("factor_time_scale", np.full(len(EFFORT_NAMES), np.nan), "must be finite")):
        np.savez(tmp_path / "bad.npz", **dict(data, **{key: value}))
        with pytest.raises(DoodleError, match=said):
            load(tmp_path / "bad.npz")
    meta = json.loads(str(data["meta"]))
    meta["effort_names"] = meta["effort_names"][:-1]
    np.savez(tmp_path / "names.npz", **dict(data, meta=np.array(json.dumps(meta))))
    with pytest.raises(DoodleError, match="other Effort features"):
        load(tmp_path / "names.npz")
    without = {k: v for k, v in data.items() if k != "factor_weight_bias"}
    np.savez(tmp_path / "old.npz", **without)
    with pytest.raises(DoodleError, match="'factor_weight_bias' is missing"):
        load(tmp_path / "old.npz")


def test_cross_procedure_evaluation_on_two_halves(tmp_path, monkeypatch):
    """The protocol end to end on four clips of the built-in library, two per half: every
    run is tested on the other procedure and the other half, and the tables, State
    confusions and reliability come out whole."""
    import shutil
    from pathlib import Path

    from doodle.app import effort_corpus as ec

    clips = Path(__file__).resolve().parents[1] / "library" / "builtin" / "clips"
    for half, names in (("one", ("punch", "greet")), ("two", ("slap", "throw"))):
        (tmp_path / half).mkdir()
        for n in names:
            shutil.copy(clips / f"{n}.bvh", tmp_path / half / f"{half}_{n}_normal_001.bvh")
    generator = ec.generator_items
    monkeypatch.setattr(ec, "generator_items", lambda part="train": generator(part, people=1))
    rep = ec.cross_procedure(tmp_path, variants=1, rates=(30.0,), scales={"human": 1.0})
    names = [r["name"] for r in rep["runs"]]
    assert names[0] == "generator + emote (one) → stylize (two)" and len(names) == 6
    for run in rep["runs"][:4]:
        train, test = run["name"].split(" → ")
        assert train.split(" ")[-1].strip("()") != test.split(" ")[-1].strip("()")  # other clips
        assert train.split(" ")[2] != test.split(" ")[0]  # the other procedure
        cell = run["cells"]["human @ 30 Hz"]
        assert 0 <= cell["state"] <= min(cell["time"], cell["weight"]) <= 1 and cell["n"] == run["test"] > 0
    assert set(rep["pooled"]) == {"emote → stylize", "stylize → emote", "generator → emote", "generator → stylize"}
    lines = ec.table(rep)
    assert any("thesis" in line for line in lines) and any("human @ 30 Hz" in line for line in lines)
    rel = ec.reliability(rep)
    assert sum(b["n"] for b in rel["time"]["bins"]) == rel["time"]["n"] > 0 and 0 <= rel["weight"]["ece"] <= 0.5
    conf = ec.state_confusion(rep)
    assert sum(map(sum, conf["emote → stylize"])) == sum(r["test"] for r in rep["runs"][:2])



def test_held_out_clips_are_tested_on_both_procedures(tmp_path, monkeypatch):
    """Trained on one procedure (or both) applied to every clip of one folder, tested on both
    applied to the clips of another (named anything): six runs, each on clips it never saw;
    and each procedure learnt on the other test clips, each clip decided by the model that
    left it out — left out, not failed, when there is one test clip."""
    import shutil
    from pathlib import Path

    from doodle.app import effort_corpus as ec

    clips = Path(__file__).resolve().parents[1] / "library" / "builtin" / "clips"
    (tmp_path / "train" / "one").mkdir(parents=True)
    (tmp_path / "test").mkdir()
    for n in ("punch", "greet"):
        shutil.copy(clips / f"{n}.bvh", tmp_path / "train" / "one" / f"one_{n}_normal_001.bvh")
    for n in ("slap", "throw"):
        shutil.copy(clips / f"{n}.bvh", tmp_path / "test" / f"{n}.bvh")
    generator = ec.generator_items
    monkeypatch.setattr(ec, "generator_items", lambda part="train": generator(part, people=1))
    rep = ec.held_out(tmp_path / "train", tmp_path / "test", variants=1, rates=(30.0,), scales={"human": 1.0})
    assert rep["clips"] == ["slap", "throw"]
    assert set(rep["pooled"]) == {"emote → emote", "emote → stylize", "stylize → emote", "stylize → stylize",
                                  "emote + stylize → emote", "emote + stylize → stylize",
                                  "emote on the other clips → emote", "stylize on the other clips → stylize"}
    for run in rep["runs"]:
        cell = run["cells"]["human @ 30 Hz"]
        assert 0 <= cell["state"] <= min(cell["time"], cell["weight"]) <= 1 and cell["n"] == run["test"] > 0
    shipped = ec.shipped_groups(rep)
    assert shipped == ("emote + stylize → emote", "emote + stylize → stylize")
    rel = ec.reliability(rep, shipped)  # the shipped model's recipe alone
    assert rel["weight"]["n"] == sum(r["test"] for r in rep["runs"] if r["group"] in shipped)
    title = ec.held_out_title(rep)
    assert "every clip of train" in title and "the 2 clips of test" in title and "other clips of test" in title
    assert ec.table(rep, title)[0].startswith(title)
    (tmp_path / "test" / "throw.bvh").unlink()  # one test clip: nothing to learn a procedure on beside it
    rep = ec.held_out(tmp_path / "train", tmp_path / "test", variants=1, rates=(30.0,), scales={"human": 1.0})
    assert set(rep["pooled"]) == {"emote → emote", "emote → stylize", "stylize → emote", "stylize → stylize",
                                  "emote + stylize → emote", "emote + stylize → stylize"}


def test_laban_eval_refuses_held_out_clips_it_cannot_read(tmp_path, capsys):
    """``doodle laban eval --held-out`` names the folder that is not one, holds no clip or a
    broken one, before minutes of work, and exits 1 without a traceback."""
    from doodle.app.cli.main import main

    (tmp_path / "empty").mkdir()
    (tmp_path / "file.bvh").write_text("HIERARCHY\n")
    (tmp_path / "broken").mkdir()
    (tmp_path / "broken" / "x.bvh").write_text("HIERARCHY\n")
    for where, says in (("empty", "empty: no motion capture clips (*.bvh) (--held-out)"),
                        ("broken", "broken/x.bvh:1: missing ROOT after HIERARCHY"),
                        ("file.bvh", "file.bvh: no such folder (--held-out)"),
                        ("missing", "missing: no such folder (--held-out)")):
        assert main(["laban", "eval", "--people", "1", "--held-out", str(tmp_path / where),
                     "-o", str(tmp_path / "ev")]) == 1
        err = capsys.readouterr().err
        assert f"{tmp_path}/{says}" in err and "Traceback" not in err


def _rest_stroke(duration, shape="minjerk", rate=90.0, pause=0.5):
    """Rest, one stroke of ``duration`` s whose speed is a minimum-jerk bell, a peaked
    ``sin^6`` (energy packed in the peak) or a flat-topped ``sin^0.8``, rest."""
    t = np.arange(0.0, duration + 2 * pause, 1 / rate)
    u = np.clip((t - pause) / duration, 0, 1)
    if shape == "minjerk":
        s = 10 * u**3 - 15 * u**4 + 6 * u**5
    else:
        grid = np.linspace(0, 1, 2001)
        g = np.sin(np.pi * grid) ** {"peaked": 6.0, "flat": 0.8}[shape]
        c = np.concatenate([[0.0], np.cumsum(0.5 * (g[1:] + g[:-1]))])
        s = np.interp(u, grid, c / c[-1])
    return t, np.column_stack([0.4 * s, 0.1 * s, 0 * s])


def _named(f, *names):
    return np.array([f[EFFORT_NAMES.index(n)] for n in names])


WEIGHT_SHAPE = ("Stroke Peakedness", "Stroke Peak Accel", "Stroke Impact", "Stroke Jerk", "Stroke Brake Ratio")


def test_stroke_weight_features_are_free_of_tempo_and_time_features_are_not():
    """Weight reads the shape of the speed curve, not how long it takes: the same
    minimum-jerk stroke made in 0.6 s or in 2 s has the same Weight features, and Time's
    stroke duration and rise differ by the ratio of the durations."""
    quick, slow = effort_features(*_rest_stroke(0.6)), effort_features(*_rest_stroke(2.0))
    np.testing.assert_allclose(_named(quick, *WEIGHT_SHAPE), _named(slow, *WEIGHT_SHAPE), atol=0.2)
    np.testing.assert_allclose(_named(quick, *WEIGHT_SHAPE[:3]), _named(slow, *WEIGHT_SHAPE[:3]), atol=0.03)
    ratio = _named(slow, "Stroke Duration", "Stroke Rise") - _named(quick, "Stroke Duration", "Stroke Rise")
    np.testing.assert_allclose(ratio, np.log(2.0 / 0.6), atol=0.1)


@pytest.mark.parametrize("duration", [0.5, 1.0, 2.5])
def test_energy_packed_in_a_peak_reads_as_concentrated(duration):
    peaked = effort_features(*_rest_stroke(duration, "peaked"))
    flat = effort_features(*_rest_stroke(duration, "flat"))
    for name in ("Stroke Peakedness", "Peak Energy Ratio", "Speed Variation"):
        assert _named(peaked, name)[0] > _named(flat, name)[0] + 0.03, name


@settings(max_examples=20, deadline=None)
@given(st.integers(0, 10_000), st.floats(30.0, 144.0), st.floats(0.1, 10.0))
def test_stroke_features_are_unchanged_by_size_and_tracking_rate(k, rate, s):
    """The per-stroke features of the same movement tracked at 30–144 Hz (jittered clock) at
    any size stay within a tenth (log units) of its 90 Hz reading; stroke counts may differ
    by a wobble, so the energy-weighted means are compared, not the strokes one by one."""
    t, p, q = _take(k)
    rng = np.random.default_rng(k)
    names = ("Stroke Duration", "Stroke Rise", "Stroke Peakedness")
    ref = _named(effort_features(*presented(t, p, q, 1.0, 90.0, rng, noise=0.0)[:2]), *names)
    got = _named(effort_features(*presented(t, p, q, s, rate, rng, noise=0.0)[:2]), *names)
    np.testing.assert_allclose(got, ref, atol=0.1)


def test_a_factor_a_procedure_did_not_give_is_left_out_of_its_fit():
    """Paths labelled 0 for Time (the stylisation operators' non-acting limbs) train the
    Weight classifier only; what was chosen is reported, among the fixed candidates."""
    from laban.factors import CANDIDATES, fit_factors

    rng = np.random.default_rng(0)
    n, d = 200, len(EFFORT_NAMES)
    X = rng.normal(size=(n, d))
    yt = np.where(X[:, EFFORT_NAMES.index("Stroke Duration")] < 0, 1, -1)
    yw = np.where(X[:, EFFORT_NAMES.index("Stroke Peakedness")] > 0, 1, -1)
    groups = np.array([f"{'a' if i % 2 else 'b'}/clip{i % 10}" for i in range(n)])
    yt_unknown = yt.copy()
    yt_unknown[100:] = 0
    X2 = X.copy()
    X2[100:, EFFORT_NAMES.index("Stroke Duration")] = 50.0  # would wreck Time if they were used for it
    report = {}
    got = fit_factors(X2, yt_unknown, yw, groups, report=report)
    assert report["time"]["features"] in CANDIDATES["time"] and report["weight"]["features"] in CANDIDATES["weight"]
    assert report["time"]["held_out"] == "sources"
    assert np.mean((got["time"].probability(X[:100]) >= 0.5) == (yt[:100] > 0)) > 0.9
    assert np.mean((got["weight"].probability(X) >= 0.5) == (yw > 0)) > 0.9


def test_the_worst_held_out_source_chooses_the_features(monkeypatch):
    """Of two candidate sets, one reads source a perfectly and source b barely (a better MEAN
    over the two sources held out in turn), the other reads both fairly: the model must carry
    to a procedure it never saw, so the second is chosen."""
    from laban import factors

    rng = np.random.default_rng(3)
    n = 400
    y = np.tile([-1, 1], n)
    source = np.repeat(["a", "b"], n)
    X = rng.normal(size=(2 * n, len(EFFORT_NAMES)))
    one, both = EFFORT_NAMES.index("Stroke Peakedness"), EFFORT_NAMES.index("Energy Spread")
    X[:, one] += np.where(source == "a", 6.0, 0.25) * y  # near perfect in a, about 0.6 in b
    X[:, both] += 0.7 * y  # about 0.7 in both
    groups = np.array([f"{s}/clip{i % 10}" for i, s in enumerate(source)])
    monkeypatch.setitem(factors.CANDIDATES, "weight", {"one source": ("Stroke Peakedness",),
                                                       "both sources": ("Energy Spread",)})
    name, _, scores, _ = factors.choose(X, y, np.ones(2 * n), groups, "weight")
    assert name == "both sources", scores


def test_each_held_out_clip_is_decided_by_the_model_that_left_it_out(monkeypatch):
    """The legibility runs: a clip's paths are decided by the model trained on the OTHER clips
    only (a fake trainer whose probabilities name the clips it saw)."""
    from dataclasses import dataclass

    import numpy as np

    import laban.train
    from doodle.app import effort_corpus as ec
    from laban.procedures import Effortful

    @dataclass
    class Fake:
        p: float

        def probability(self, X):
            return np.full(len(X), self.p)

    def train(items, seed=0):
        saw = {it.group for it in items}
        return {"time": Fake(0.9 if saw == {"b"} else 0.1), "weight": Fake(0.9 if "a" in saw else 0.1)}

    monkeypatch.setattr(laban.train, "train_factors", train)
    t = np.linspace(0.0, 1.0, 60)
    path = np.stack([np.sin(3 * t), t, 0 * t], axis=1)
    q = np.tile([0.0, 0.0, 0.0, 1.0], (60, 1))
    items = [Effortful(t, path, q, 1, -1, "emote", g) for g in ("a", "b")]
    cells = ec._left_out_cells(items, items, [("human @ 30 Hz", 1.0, 30.0)], 0.6, 0)["human @ 30 Hz"]
    # clip a: decided by the model that saw b alone (Sudden 0.9, Strong 0.1): both right
    # clip b: decided by the model that saw a alone (Sudden 0.1, Strong 0.9): both wrong
    assert cells["p_sudden"] == [0.9, 0.1] and cells["p_strong"] == [0.1, 0.9]
    assert cells["time"] == 0.5 and cells["weight"] == 0.5 and cells["state"] == 0.5
