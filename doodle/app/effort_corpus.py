"""Effort-labelled paths grounded in real movement, and the cross-procedure evaluation.

Real neutral movement: the ``*_normal_*`` clips of the Bandai Namco motion dataset (read, never
copied: ``--mocap DIR``). Each clip gives up to three paths — right hand, left hand and root
(pelvis) — that move at least :data:`REACH` at the performer's scale. Effort is applied to
them by two independent procedures:

* ``emote`` — the EMOTE-style timing of :mod:`laban.procedures` on each path;
* ``stylize`` — the thesis's stylisation operators (§5.4, ``retarget.stylize``) on the whole
  skeleton (Time: stage retiming and motion scales; Weight: motion scale, speed-variation
  retiming and shape), the paths read back by forward kinematics.

Each path gets every Time × Weight State, ``variants`` times at a random strength 0.6–1.

Cross-procedure protocol (:func:`cross_procedure`): a model is trained on the generator
(:mod:`laban.synth`) and ONE procedure applied to the clips of one half of the data, and
tested on the OTHER procedure applied to the clips of the other half — both ways, both
halves: never tested on a procedure, nor on a neutral clip, it was trained on. A model
trained on the generator alone is tested on both procedures beside it. Test paths are
presented at a figurine's size (×0.15) and the performer's own (×1), tracked at 30, 60, 90
and 144 Hz with clock jitter and absolute tracking noise (:func:`laban.procedures.presented`).
The cross-procedure figures were read while the Effort stage was changed; :func:`held_out`
gives the same protocol on clips nothing was chosen on (the DeepMimic capture).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from laban.procedures import RATES, Effortful, emote, presented

MOCAP = Path(__file__).resolve().parents[2].parent / "shared" / "data" / "mocap" / "bandai"
HELD_OUT = MOCAP.parent / "deepmimic"  # other performers, another capture: used by no choice (:func:`held_out`)
REACH = 0.25  # m: a path that moves less than this (box diagonal, performer's scale) is not used
PATHS = ("right_hand", "left_hand", "pelvis")
SCALES = {"figurine ×0.15": 0.15, "human ×1": 1.0}
STATES = ((1, 1), (1, -1), (-1, 1), (-1, -1))  # (time, weight): Sudden Strong … Sustained Light
SHIPPED = "emote + stylize"  # the held-out runs trained as the shipped model is (the generator and both procedures)
THESIS = {"time": "> 0.85 (Drive HMM)", "weight": "NB single factors ≥ 0.74", "state": "0.63 (HMM States)"}


@dataclass(frozen=True, eq=False)
class Clip:
    """A neutral clip: its name, which half it is in (the dataset it comes from), the motion
    and its stages, and its paths by role, each ``(t, p, q)``."""

    name: str
    half: str
    motion: object
    stages: object
    paths: dict


def neutral_clips(root=None, pattern: str = "*/*_normal_*.bvh") -> list[Clip]:
    """The neutral (``normal``) clips under ``root`` (default :data:`MOCAP`), sorted by name —
    or the files ``pattern`` names there (each clip's half is its folder's name)."""
    from retarget.analysis import guess_roles, stages
    from retarget.bvh import read_bvh

    root = Path(root) if root else MOCAP
    files = sorted(root.glob(pattern))
    clips = []
    for f in files:
        motion = read_bvh(f)
        roles = guess_roles(motion.skeleton)
        paths = _paths(motion, roles)
        if paths:
            clips.append(Clip(f.stem, f.parent.name, motion, stages(motion), paths))
    return clips


def _paths(motion, roles: dict) -> dict:
    from retarget.skeleton import forward_kinematics

    pos, rot = forward_kinematics(motion)
    t = np.arange(motion.frames) * motion.frame_time
    out = {}
    for role in PATHS:
        if role in roles:
            p = pos[:, roles[role]]
            if float(np.linalg.norm(np.ptp(p, axis=0))) >= REACH:
                out[role] = (t, p, rot[:, roles[role]])
    return out


def emote_items(clips: list[Clip], seed: int = 0, variants: int = 2) -> list[Effortful]:
    """Every path of every clip in every State by the EMOTE-style timing."""
    items = []
    for c, clip in enumerate(clips):
        for role, (t, p, q) in clip.paths.items():
            for s, (lt, lw) in enumerate(STATES):
                for v in range(variants):
                    rng = np.random.default_rng([seed, c, PATHS.index(role), s, v, 1])
                    tt, pp, qq = emote(t, p, q, lt, lw, rng, strength=float(rng.uniform(0.6, 1.0)))
                    items.append(Effortful(tt, pp, qq, lt, lw, "emote", clip.name, role))
    return items


def stylize_items(clips: list[Clip], seed: int = 0, variants: int = 2) -> list[Effortful]:
    """Every clip in every State by the thesis's stylisation operators, the paths read back
    by forward kinematics: the acting hand or foot's (role ``acting``) — the most moving one,
    whose execution stroke the Time modifier retimes (§5.4.3) — and, like
    :func:`emote_items`, each of the clip's other :data:`PATHS` (hands, pelvis) that moves.
    Weight's retiming and motion scale act on the whole skeleton, so those paths carry the
    Weight; Time's retiming follows the acting limb's execution alone (measured: a classifier
    trained on the EMOTE-style procedure reads the other paths' Time at chance, 0.47–0.75,
    against 0.80–0.83 for the acting path), so their Time is left unlabelled (0)."""
    from retarget.effort_signature import most_moving
    from retarget.analysis import guess_roles
    from retarget.skeleton import forward_kinematics
    from retarget.stylize import stylize_staged

    items = []
    for c, clip in enumerate(clips):
        acting = most_moving(clip.motion)
        roles = guess_roles(clip.motion.skeleton)
        joints = [acting] + [roles[r] for r in PATHS if r in clip.paths and roles[r] != acting]
        for s, (lt, lw) in enumerate(STATES):
            for v in range(variants):
                rng = np.random.default_rng([seed, c, s, v, 2])
                k = float(rng.uniform(0.6, 1.0))
                out, _ = stylize_staged(clip.motion, clip.stages, lt * k, lw * k)
                pos, rot = forward_kinematics(out)
                t = np.arange(out.frames) * out.frame_time
                items += [Effortful(t, pos[:, j], rot[:, j], lt if j == acting else 0, lw, "stylize", clip.name,
                                    "acting" if j == acting else next(r for r in PATHS if roles.get(r) == j))
                          for j in joints]
    return items


def generator_items(part: str = "train", **overrides) -> list[Effortful]:
    """The generator's curves (:mod:`laban.synth`) as Time / Weight labelled paths."""
    from laban.train import effortful, generated

    return effortful(generated(part, **overrides))


def decide(model_factors: dict, X: np.ndarray, threshold: float) -> dict:
    """Probabilities, decisions and abstentions of the Time and Weight classifiers on rows X."""
    out = {}
    for factor in ("time", "weight"):
        p = model_factors[factor].probability(X)
        out[factor] = {"p": p, "sign": np.where(p >= 0.5, 1, -1), "abstain": np.maximum(p, 1 - p) < threshold}
    return out


def score_cell(model_factors: dict, items: list[Effortful], scale: float, rate: float, threshold: float,
               seed: int) -> dict:
    """Time, Weight and State accuracy of ``items`` presented at ``scale`` and ``rate``, with
    abstentions (confidence under ``threshold``) and the probabilities behind each decision."""
    return cell_scores(decide(model_factors, presented_features(items, scale, rate, seed), threshold), items)


def presented_features(items: list[Effortful], scale: float, rate: float, seed: int) -> np.ndarray:
    """The Effort features of ``items`` presented at ``scale`` and ``rate`` (tracking noise
    and clock jitter drawn from ``seed``, the scale and the rate)."""
    from laban.features import effort_features

    rng = np.random.default_rng([seed, int(rate), int(scale * 1000)])
    return np.array([effort_features(*presented(it.t, it.p, it.q, scale, rate, rng)[:2]) for it in items])


def cell_scores(d: dict, items: list[Effortful]) -> dict:
    """A cell's figures (see :func:`score_cell`) from the decisions ``d`` (:func:`decide`) on ``items``."""
    yt, yw = np.array([it.time for it in items]), np.array([it.weight for it in items])
    ok_t, ok_w = d["time"]["sign"] == yt, d["weight"]["sign"] == yw
    either = d["time"]["abstain"] | d["weight"]["abstain"]
    decided_t, decided_w = ~d["time"]["abstain"], ~d["weight"]["abstain"]
    return {
        "n": len(items), "time": float(ok_t.mean()), "weight": float(ok_w.mean()), "state": float((ok_t & ok_w).mean()),
        "abstain_time": float(d["time"]["abstain"].mean()), "abstain_weight": float(d["weight"]["abstain"].mean()),
        "abstain_either": float(either.mean()),
        "time_decided": float(ok_t[decided_t].mean()) if decided_t.any() else None,
        "weight_decided": float(ok_w[decided_w].mean()) if decided_w.any() else None,
        "n_time_decided": int(decided_t.sum()), "n_weight_decided": int(decided_w.sum()),
        "p_sudden": d["time"]["p"].tolist(), "p_strong": d["weight"]["p"].tolist(),
        "truth_time": yt.tolist(), "truth_weight": yw.tolist(),
    }


def cross_procedure(root=None, seed: int = 0, variants: int = 2, threshold: float | None = None,
                    rates=RATES, scales=None, progress=None) -> dict:
    """The cross-procedure evaluation described in the module docstring: per run, scale and
    rate, the Time, Weight and State accuracies and abstentions (see :func:`score_cell`)."""
    from laban.train import THRESHOLD, train_factors

    threshold = THRESHOLD if threshold is None else threshold
    scales = scales or SCALES
    say = progress or (lambda text: None)
    clips = neutral_clips(root)
    if not clips:
        raise FileNotFoundError(f"no neutral (*_normal_*.bvh) clips under {Path(root) if root else MOCAP}")
    halves = sorted({c.half for c in clips})
    if len(halves) < 2:  # one folder: alternate clips
        halves = ["even", "odd"]
        clips = [Clip(c.name, halves[k % 2], c.motion, c.stages, c.paths) for k, c in enumerate(clips)]
    say(f"{len(clips)} neutral clips, {sum(len(c.paths) for c in clips)} paths; applying effort")
    by = {}
    for h in halves[:2]:
        part = [c for c in clips if c.half == h]
        by[("emote", h)] = emote_items(part, seed, variants)
        by[("stylize", h)] = stylize_items(part, seed, variants)
    generator = generator_items("train")

    def labelled(items):  # a test path has both Factors applied
        return [it for it in items if it.time and it.weight]

    runs = []
    for train_proc, test_proc in (("emote", "stylize"), ("stylize", "emote")):
        for a, b in ((halves[0], halves[1]), (halves[1], halves[0])):
            runs.append((f"generator + {train_proc} ({a}) → {test_proc} ({b})", generator + by[(train_proc, a)],
                         labelled(by[(test_proc, b)]), f"{train_proc} → {test_proc}"))
    both = {p: labelled(by[(p, halves[0])] + by[(p, halves[1])]) for p in ("emote", "stylize")}
    runs.append(("generator alone → emote (all)", generator, both["emote"], "generator → emote"))
    runs.append(("generator alone → stylize (all)", generator, both["stylize"], "generator → stylize"))
    report = {"clips": [c.name for c in clips], "halves": halves[:2], "threshold": threshold,
              "scales": dict(scales), "rates": list(rates), "runs": []}
    for k, (name, train_items, test_items, group) in enumerate(runs):
        say(f"run {k + 1}/{len(runs)}: {name}: training on {len(train_items)} paths")
        chosen: dict = {}
        factors = train_factors(train_items, seed=seed, report=chosen)
        cells = {}
        for sname, s in scales.items():
            for r in rates:
                cells[f"{sname} @ {r:g} Hz"] = score_cell(factors, test_items, s, r, threshold, seed + k)
        report["runs"].append({"name": name, "group": group, "train": len(train_items), "test": len(test_items),
                               "temperature": {f: factors[f].temperature for f in factors},
                               "chosen": {f: f"{c['features']}, C={c['C']:g}" for f, c in chosen.items()},
                               "cells": cells})
    report["pooled"] = pooled(report)
    return report


def held_out(root=None, test_root=None, seed: int = 0, variants: int = 2, threshold: float | None = None,
             rates=RATES, scales=None) -> dict:
    """The cross-procedure protocol on clips nothing was chosen on: models trained on the
    generator and ONE procedure applied to every neutral clip under ``root`` (default
    :data:`MOCAP`), tested on BOTH procedures applied to the clips under ``test_root``
    (default :data:`HELD_OUT`, every ``*.bvh``: the DeepMimic capture, which no feature,
    operator or constant of the Effort stage was chosen on). Beside them, two more kinds of
    run on the same test paths:

    * ``emote + stylize → …`` — the shipped model's recipe (the generator and both
      procedures on every training clip): what the default model does on clips it never saw;
    * ``P on the other clips → P`` — what the features can read of procedure P at all: a
      model trained on P applied to the other test clips alone (no generator), each clip
      tested by the model that left it out. Where this is low, P's effort is not legible in a
      single path's size- and rate-free features, whatever the training data. Only with two
      test clips or more.

    A report as :func:`cross_procedure`'s."""
    from laban.train import THRESHOLD, train_factors

    threshold = THRESHOLD if threshold is None else threshold
    scales = scales or SCALES
    cells = [(f"{sname} @ {r:g} Hz", s, r) for sname, s in scales.items() for r in rates]
    train_clips, test_clips = neutral_clips(root), neutral_clips(test_root or HELD_OUT, "*.bvh")
    if not train_clips or not test_clips:
        raise FileNotFoundError("held_out needs neutral clips to train on and clips to test on")
    procedures = {"emote": emote_items, "stylize": stylize_items}
    made = {p: make(test_clips, seed, variants) for p, make in procedures.items()}
    tests = {p: [it for it in items if it.time and it.weight] for p, items in made.items()}
    trained = {p: make(train_clips, seed, variants) for p, make in procedures.items()}
    generator = generator_items("train")
    report = {"clips": [c.name for c in test_clips], "trained_on": str(root or MOCAP),
              "tested_on": str(test_root or HELD_OUT), "threshold": threshold, "scales": dict(scales),
              "rates": list(rates), "runs": []}
    recipes = [(p, generator + trained[p]) for p in procedures]
    recipes.append((SHIPPED, generator + trained["emote"] + trained["stylize"]))
    for k, (name, items) in enumerate(recipes):
        factors = train_factors(items, seed=seed)
        for test_proc, test in tests.items():
            report["runs"].append({
                "name": f"generator + {name} → {test_proc} (held-out clips)", "group": f"{name} → {test_proc}",
                "test": len(test),
                "cells": {c: score_cell(factors, test, s, r, threshold, seed + k) for c, s, r in cells}})
    for k, (proc, test) in enumerate(tests.items()):
        if len({it.group for it in test}) < 2:
            continue
        report["runs"].append({"name": f"{proc} on the other held-out clips → {proc} (leave one clip out)",
                               "group": f"{proc} on the other clips → {proc}", "test": len(test),
                               "cells": _left_out_cells(made[proc], test, cells, threshold, seed + k)})
    report["pooled"] = pooled(report)
    return report


def _left_out_cells(items: list[Effortful], test: list[Effortful], cells, threshold: float, seed: int) -> dict:
    """Per cell, the figures of ``test`` when each clip's paths are decided by a model trained
    on the ``items`` of the other clips (:func:`held_out`'s legibility runs)."""
    from laban.train import train_factors

    group = np.array([it.group for it in test])
    folds = {g: train_factors([it for it in items if it.group != g], seed=seed) for g in sorted(set(group))}
    out = {}
    for name, s, r in cells:
        X = presented_features(test, s, r, seed)
        d = {f: {"p": np.zeros(len(test)), "sign": np.zeros(len(test), int), "abstain": np.zeros(len(test), bool)}
             for f in ("time", "weight")}
        for g, factors in folds.items():
            rows = group == g
            for f, part in decide(factors, X[rows], threshold).items():
                for key, value in part.items():
                    d[f][key][rows] = value
        out[name] = cell_scores(d, test)
    return out


def held_out_title(report: dict) -> str:
    """The title of :func:`held_out`'s table."""
    train, test = Path(report["trained_on"]).name, Path(report["tested_on"]).name
    return (f"Held-out clips: trained on one procedure (or both, as the shipped model) applied to every clip of "
            f"{train}, tested on both applied to the {len(report['clips'])} clips of {test} (no Effort choice was "
            f"made on them); last, each procedure learnt on the other clips of {test} (leave one clip out): how "
            "much of it the features can read at all")


def pooled(report: dict) -> dict:
    """Per group of runs (``emote → stylize`` …) and cell: accuracies weighted by test size."""
    out = {}
    for run in report["runs"]:
        g = out.setdefault(run["group"], {})
        for cell, r in run["cells"].items():
            acc = g.setdefault(cell, {"n": 0, "time": 0.0, "weight": 0.0, "state": 0.0, "abstain_either": 0.0,
                                      "abstain_time": 0.0, "abstain_weight": 0.0, "time_decided": 0.0,
                                      "weight_decided": 0.0, "n_time_decided": 0, "n_weight_decided": 0})
            for key in ("time", "weight", "state", "abstain_either", "abstain_time", "abstain_weight"):
                acc[key] += r[key] * r["n"]
            acc["n"] += r["n"]
            for f in ("time", "weight"):
                acc[f"{f}_decided"] += (r[f"{f}_decided"] or 0.0) * r[f"n_{f}_decided"]
                acc[f"n_{f}_decided"] += r[f"n_{f}_decided"]
    for g in out.values():
        for acc in g.values():
            for key in ("time", "weight", "state", "abstain_either", "abstain_time", "abstain_weight"):
                acc[key] /= max(acc["n"], 1)
            for f in ("time", "weight"):
                n = acc[f"n_{f}_decided"]
                acc[f"{f}_decided"] = acc[f"{f}_decided"] / n if n else None
    return out


def table(report: dict, title: str = "Cross-procedure Effort accuracy (trained on one procedure, tested on the "
                                     "other and on other clips") -> list[str]:
    """The pooled cross-procedure tables as text lines, the thesis's figures beside them."""
    lines = [f"{title}; chance: Time 0.5, Weight 0.5, State 0.25; abstention below confidence "
             f"{report['threshold']:g})",
             f"  thesis (recorded performances): Time {THESIS['time']}, {THESIS['weight']}, States {THESIS['state']}"]
    lines.append("  (time, weight, state: every path, its quality's sign even where it abstains; abstain: either "
                 "quality left neutral; decided: accuracy where the quality is applied)")

    def num(x):
        return f"{x:6.3f}" if x is not None else "     -"

    for group, cells in report["pooled"].items():
        lines.append(f"  {group}")
        lines.append(f"    {'scale @ rate':<28} {'n':>5} {'time':>6} {'weight':>6} {'state':>6} {'abstain':>8}"
                     f"   decided: {'time':>6} {'weight':>6}")
        for cell, r in cells.items():
            lines.append(f"    {cell:<28} {r['n']:5d} {r['time']:6.3f} {r['weight']:6.3f} {r['state']:6.3f} "
                         f"{r['abstain_either']:8.3f}            {num(r['time_decided'])} {num(r['weight_decided'])}")
    return lines


def shipped_groups(report: dict) -> tuple[str, ...]:
    """The groups of :func:`held_out`'s runs trained as the shipped model is."""
    return tuple(run["group"] for run in report["runs"] if run["group"].startswith(f"{SHIPPED} → "))


def reliability(report: dict, groups=None, bins: int = 10) -> dict:
    """Reliability of the decisions' confidences, pooled over the cross-procedure runs'
    cells (or those of the runs in ``groups``): per confidence bin, the mean confidence, the
    share right and the count, for Time and Weight; and the expected calibration error."""
    out = {}
    for factor, key, truth in (("time", "p_sudden", "truth_time"), ("weight", "p_strong", "truth_weight")):
        p, y = [], []
        for run in report["runs"]:
            if groups is None and run["group"].startswith("generator"):
                continue
            if groups is not None and run["group"] not in groups:
                continue
            for r in run["cells"].values():
                p += r[key]
                y += r[truth]
        p, y = np.array(p), np.array(y)
        conf = np.maximum(p, 1 - p)
        right = np.where(p >= 0.5, 1, -1) == y
        edges = np.linspace(0.5, 1.0, bins + 1)
        idx = np.clip(np.digitize(conf, edges) - 1, 0, bins - 1)
        rows = [{"low": float(edges[b]), "high": float(edges[b + 1]), "n": int((idx == b).sum()),
                 "confidence": float(conf[idx == b].mean()) if (idx == b).any() else None,
                 "accuracy": float(right[idx == b].mean()) if (idx == b).any() else None} for b in range(bins)]
        ece = float(sum(r["n"] * abs(r["confidence"] - r["accuracy"]) for r in rows if r["n"]) / max(len(p), 1))
        out[factor] = {"bins": rows, "ece": ece, "n": int(len(p))}
    return out


def state_confusion(report: dict) -> dict:
    """Per group of cross-procedure runs, the State confusion matrix (rows: truth, in the
    order of :data:`laban.efforts.STATES`) pooled over every cell."""
    from laban.efforts import STATES as NAMES, state_of

    out = {}
    for run in report["runs"]:
        m = out.setdefault(run["group"], np.zeros((4, 4), int))
        for r in run["cells"].values():
            for ps, pw, yt, yw in zip(r["p_sudden"], r["p_strong"], r["truth_time"], r["truth_weight"]):
                a = NAMES.index(state_of(yt, yw))
                b = NAMES.index(state_of(1 if ps >= 0.5 else -1, 1 if pw >= 0.5 else -1))
                m[a, b] += 1
    return {g: m.tolist() for g, m in out.items()}


# --- A proxy check on real people's effort: Bandai Namco's styled clips --------------------------
#
# No effort-labelled motion capture is at hand, but the Bandai Namco dataset has the same
# contents (bow, bye, walk, run, …) performed in styles by actors. High-arousal styles
# (angry, active, proud) are performed quicker and more forcefully than low-arousal ones
# (tired, sad, not-confident): a PROXY for Sudden vs Sustained and Strong vs Light, not a
# label — sad and tired are, in Laban's terms, rather "passive weight" (giving in to gravity)
# than Light, and a proud walk need not be Sudden. Nothing in the features, candidates or
# training was chosen on these clips. Figures: for every content, each (high, low) pair of
# clips — is P(Sudden) / P(Strong) higher for the high-arousal clip (threshold-free, like an
# AUC; chance 0.5) — and the share of clips whose decided quality matches the proxy.

HIGH_AROUSAL = ("angry", "active", "proud")
LOW_AROUSAL = ("tired", "sad", "not-confident")


def styled_clips(root=None) -> list[tuple[str, str, str, tuple]]:
    """``(content, style, name, (t, p, q))`` for each styled clip of the proxy's styles under
    ``root``: the path of the clip's most moving hand or foot (as a one-track doodle)."""
    from retarget.bvh import read_bvh
    from retarget.effort_signature import most_moving
    from retarget.skeleton import forward_kinematics

    root = Path(root) if root else MOCAP
    out = []
    for f in sorted(root.glob("*/*.bvh")):
        parts = f.stem.split("_")
        if len(parts) < 4 or parts[-2] not in HIGH_AROUSAL + LOW_AROUSAL:
            continue
        motion = read_bvh(f)
        pos, rot = forward_kinematics(motion)
        j = most_moving(motion, pos)
        t = np.arange(motion.frames) * motion.frame_time
        out.append((parts[-3], parts[-2], f.stem, (t, pos[:, j], rot[:, j])))
    return out


def styled_proxy(model_factors: dict, threshold: float, clips=None, root=None, scales=None,
                 rates=(30.0, 90.0), seed: int = 0) -> dict:
    """The proxy figures (see above) of the Time and Weight classifiers ``model_factors``
    on the styled clips, per presentation (scale and rate)."""
    from laban.features import effort_features
    from laban.procedures import presented

    clips = styled_clips(root) if clips is None else clips
    scales = scales or SCALES
    out = {"clips": len(clips), "contents": len({c[0] for c in clips}), "cells": {}}
    if not clips:
        return out
    for sname, s in scales.items():
        for r in rates:
            rng = np.random.default_rng([seed, int(r), int(s * 1000), 7])
            X = np.array([effort_features(*presented(*path, s, r, rng)[:2]) for *_, path in clips])
            d = decide(model_factors, X, threshold)
            high = np.array([c[1] in HIGH_AROUSAL for c in clips])
            content = np.array([c[0] for c in clips])
            cell = {}
            for factor in ("time", "weight"):
                p = d[factor]["p"]
                wins = [float(p[i] > p[k]) + 0.5 * float(p[i] == p[k])
                        for i in np.flatnonzero(high) for k in np.flatnonzero(~high) if content[i] == content[k]]
                agree = d[factor]["sign"] == np.where(high, 1, -1)
                decided = ~d[factor]["abstain"]
                cell[factor] = {"pairs": len(wins), "ordered": float(np.mean(wins)) if wins else None,
                                "agree": float(agree.mean()),
                                "agree_decided": float(agree[decided].mean()) if decided.any() else None,
                                "abstain": float(d[factor]["abstain"].mean())}
            out["cells"][f"{sname} @ {r:g} Hz"] = cell
    return out


def proxy_table(proxy: dict) -> list[str]:
    """The proxy figures as text lines."""
    lines = [f"Proxy (not effort labels): {proxy['clips']} Bandai styled clips, {proxy['contents']} contents, "
             f"{'/'.join(HIGH_AROUSAL)} vs {'/'.join(LOW_AROUSAL)}: the high-arousal clip of a pair read more "
             "Sudden / Strong (chance 0.5); share of clips decided as the proxy says",
             f"    {'scale @ rate':<28} {'time pairs':>10} {'agree':>6} {'weight pairs':>12} {'agree':>6}"]
    def num(x, width):
        return f"{x:{width}.3f}" if x is not None else " " * (width - 1) + "-"

    for cell, r in proxy["cells"].items():
        lines.append(f"    {cell:<28} {num(r['time']['ordered'], 10)} {num(r['time']['agree'], 6)} "
                     f"{num(r['weight']['ordered'], 12)} {num(r['weight']['agree'], 6)}")
    return lines
