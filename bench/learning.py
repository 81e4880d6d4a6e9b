"""(Superseded in ``make bench`` by :mod:`bench.learning_protocol`, which measures the
product path — ``doodle learn`` and ``doodle recognize`` — with every constant held out;
this older bench classifies isolated gestures by an argmin over all classes, not as the
product does, and its constants were set on the same users.)

Learning gestures (§4.2.5–4.2.6) on the real Vive recordings of ../shared/data/vive-gestures:
learning time; isolated-gesture accuracy user-dependent (learn from ex_0..2, test ex_3, ex_4)
and user-independent (learn from the other users' ex_0..2), with one controller (c0) and
both; the DTW nearest-neighbour baseline in the same run (direction vectors of the paths
resampled to 32 points, 3 templates per class); recognition time per gesture beside the
baseline's; continuous recognition of streams of held-out recordings joined by pauses and
transitions (precision, recall, F1). A confusion matrix goes to out/bench/learning_c0.png.

Isolated gestures are classified as the product classifies a learned action's segment
(:mod:`grammar.shapes`): the smallest ``edits + WEIGHT × shape distance`` — edit distance
from the token string to each learned expression's language plus the DTW distance of the
path's directions to the action's examples' (both controllers: the sum over the two); the
token-only classifier (edits alone) is printed beside it. Streams go through the Matcher
with the learned actions' tolerances, then the shape Refiner, as ``doodle recognize`` does.
"""

import time
from collections import defaultdict
from pathlib import Path

import numpy as np

from doodle.input.csvimport import read_csv
from doodle.core.model import Track
from grammar import shapes
from grammar.learn import _automaton, _dtw_cost, _run, learn, token_string

CAP = 40.0  # edit distances are exact up to this

ROOT = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "vive-gestures"
OUT = Path(__file__).resolve().parents[1] / "out" / "bench"


def _examples(doodles, track):
    return [(d.track(track).t, d.track(track).p, d.track(track).q) for d in doodles]


def directions(d, tracks, points=32):
    """The baseline's representation: unit direction vectors of each path resampled by arc length."""
    cols = []
    for tr in tracks:
        p = d.track(tr).p
        s = np.concatenate([[0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))])
        u = np.linspace(0, s[-1], points)
        r = np.column_stack([np.interp(u, s, p[:, k]) for k in range(3)])
        v = np.diff(r, axis=0)
        cols.append(v / np.maximum(np.linalg.norm(v, axis=1, keepdims=True), 1e-9))
    return np.hstack(cols)


def main() -> None:
    files = sorted(ROOT.glob("*/*/*.csv"))
    if not files:
        print(f"Learning gestures: no data under {ROOT}")
        return
    data = defaultdict(lambda: defaultdict(list))
    for path in files:
        data[path.parts[-3]][path.parts[-2]].append(read_csv(path, convention="unity"))
    users = sorted(data)
    classes = sorted(data[users[0]])
    print(f"Learning gestures ({len(users)} users × {len(classes)} gestures, real Vive recordings)")

    learned, took = {}, []
    for user in users:
        for g in classes:
            for tr in ("c0", "c1"):
                start = time.perf_counter()
                learned[(user, g, tr)] = learn(_examples(data[user][g][:3], tr), data[user][g][0].rate)
                took.append(time.perf_counter() - start)
    print(f"  learning one action from 3 examples: mean {np.mean(took) * 1000:.0f} ms, max {np.max(took) * 1000:.0f} ms "
          "(target ≤ 100 ms)")

    automata, shape_sets = {}, {}

    def ours(user_models, d, tracks):
        """Per class: (edits, edits + WEIGHT × shape distance), summed over the tracks."""
        edits = total = 0.0
        for tr in tracks:
            key = tuple(user_models[(g, tr)].expression for g in classes)
            if key not in automata:  # built once per user and track
                automata[key] = _automaton(list(key), CAP)
                shape_sets[key] = shapes.shape_set({g: user_models[(g, tr)].paths for g in classes},
                                                   dict(zip(classes, key)), automaton=automata[key])
            e = _run(automata[key], token_string(d.track(tr), d.rate))
            x = shapes.directions(shapes.resample(d.track(tr).p))
            edits, total = edits + e, total + e + shapes.WEIGHT * shape_sets[key].distances(x)
        return edits, total

    results = {}
    confusion = np.zeros((len(classes), len(classes)), dtype=int)
    times = {"ours": [], "dtw": []}
    for tracks in (("c0",), ("c0", "c1")):
        right = {"ours": 0, "tokens": 0, "dtw": 0}
        n = 0
        for user in users:
            models = {(g, tr): learned[(user, g, tr)] for g in classes for tr in tracks}
            templates = [(g, directions(d, tracks)) for g in classes for d in data[user][g][:3]]
            for truth, exs in data[user].items():
                for d in exs[3:5]:
                    start = time.perf_counter()
                    edits, total = ours(models, d, tracks)
                    guess = classes[int(np.argmin(total))]
                    times["ours"].append(time.perf_counter() - start)
                    start = time.perf_counter()
                    x = directions(d, tracks)
                    base = min(templates, key=lambda tpl: _dtw_cost(x, tpl[1]))[0]
                    times["dtw"].append(time.perf_counter() - start)
                    right["ours"] += guess == truth
                    right["tokens"] += classes[int(np.argmin(edits))] == truth
                    right["dtw"] += base == truth
                    n += 1
                    if tracks == ("c0",):
                        confusion[classes.index(truth), classes.index(guess)] += 1
        results[tracks] = (right["ours"] / n, right["tokens"] / n, right["dtw"] / n, n)
    for tracks, (acc, tokens_only, base, n) in results.items():
        target = "≥ 0.90" if len(tracks) == 1 else "≥ 0.97"
        print(f"  user-dependent, {'+'.join(tracks):<6} accuracy {acc:.3f} over {n}  (target {target}; "
              f"DTW baseline {base:.3f}; tokens alone {tokens_only:.3f})")

    independent = {}
    for tracks in (("c0",), ("c0", "c1")):
        right = tokens_right = n = base = 0
        for user in users:
            others = [u for u in users if u != user][:3]  # the baseline's 3 templates: ex_0 of three others
            templates = [(g, directions(data[u][g][0], tracks)) for g in classes for u in others]
            models = {}
            for g in classes:
                for tr in tracks:
                    if (user, g, tr) not in independent:
                        pool = [d for other in users if other != user for d in data[other][g][:3]]
                        independent[(user, g, tr)] = learn(_examples(pool, tr), pool[0].rate, with_tolerance=False)
                    models[(g, tr)] = independent[(user, g, tr)]
            for truth, exs in data[user].items():
                for d in exs[3:5]:
                    edits, total = ours(models, d, tracks)
                    right += classes[int(np.argmin(total))] == truth
                    tokens_right += classes[int(np.argmin(edits))] == truth
                    x = directions(d, tracks)
                    base += min(templates, key=lambda tpl: _dtw_cost(x, tpl[1]))[0] == truth
                    n += 1
        print(f"  user-independent, {'+'.join(tracks):<6} accuracy {right / n:.3f} over {n} (learned from the other "
              f"{len(users) - 1} users' 3 examples each; DTW baseline {base / n:.3f}; tokens alone {tokens_right / n:.3f})")
    print(f"  recognition time per gesture: ours {np.median(times['ours']) * 1000:.1f} ms, "
          f"DTW baseline {np.median(times['dtw']) * 1000:.1f} ms (medians)")
    _confusion_picture(confusion, classes)
    _continuous(data, users, classes, learned)


def _confusion_picture(confusion, classes) -> None:
    try:
        from laban.report import confusion_png

        OUT.mkdir(parents=True, exist_ok=True)
        path = confusion_png(confusion, classes, OUT / "learning_c0.png", "learned gestures, user-dependent, c0")
        print(f"  confusion matrix (c0, user-dependent): {path}")
    except Exception as e:  # a picture is a bonus here
        print(f"  (no confusion picture: {e})")


def _continuous(data, users, classes, learned, pause=1.0, seed=0) -> None:
    """Streams: each user's held-out recordings (ex_3, ex_4 of every class) in a shuffled
    order, each translated to start where the previous ended, joined by a still pause with
    tracking noise and a 0.4 s move; recognised by the Matcher with the learned actions."""
    from doodle.input.segmenter import tokenize
    from grammar.matcher import match
    from grammar.library import compile_library
    from library.manifest import ActionDef, Library

    rng = np.random.default_rng(seed)
    runs = []
    for user in users:
        library = Library(user, tuple(ActionDef(g, learned[(user, g, "c0")].expression, False, True, False,
                                                tolerance=learned[(user, g, "c0")].tolerance) for g in classes), "")
        auto = compile_library(library).automaton()
        shape_set = shapes.shape_set({g: learned[(user, g, "c0")].paths for g in classes},
                                     {g: learned[(user, g, "c0")].expression for g in classes})
        pieces = [(g, d.track("c0")) for g in classes for d in data[user][g][3:5]]
        order = rng.permutation(len(pieces))
        t_parts, p_parts, q_parts, spans = [], [], [], []
        clock, where, q_last = 0.0, np.zeros(3), np.array([0.0, 0.0, 0.0, 1.0])
        rate = 90.0
        for k in order:
            g, tr = pieces[k]
            n_pause = int(pause * rate)
            t_parts.append(clock + np.arange(n_pause) / rate)
            p_parts.append(where + rng.normal(0, 3e-4, (n_pause, 3)))
            q_parts.append(np.tile(q_last, (n_pause, 1)))
            clock += n_pause / rate
            n_move = int(0.4 * rate)
            target_q = tr.q[0] * np.sign(np.dot(tr.q[0], q_last) or 1.0)
            w = (0.5 - 0.5 * np.cos(np.linspace(0, np.pi, n_move)))[:, None]
            t_parts.append(clock + np.arange(n_move) / rate)
            p_parts.append(np.repeat(where[None], n_move, 0))
            qm = (1 - w) * q_last + w * target_q
            q_parts.append(qm / np.linalg.norm(qm, axis=1, keepdims=True))
            clock += n_move / rate
            shift = where - tr.p[0]
            t_parts.append(clock + (tr.t - tr.t[0]))
            p_parts.append(tr.p + shift)
            q_parts.append(tr.q)
            spans.append((g, clock, clock + tr.t[-1] - tr.t[0]))
            clock += tr.t[-1] - tr.t[0] + 1.0 / rate
            where, q_last = tr.p[-1] + shift, tr.q[-1]
        t = np.concatenate(t_parts)
        stream = Track("c0", t, np.concatenate(p_parts), np.concatenate(q_parts), np.ones(len(t), dtype=bool))
        tokens = tokenize(stream, rate)
        matched = match(tokens, auto)
        refined = shapes.refine(matched, tokens, stream.p, stream.valid, shape_set)
        runs.append((t, spans, [s for s in matched if s.action != "unknown"], [s for s in refined if s.action != "unknown"]))
    precision, recall, f1 = _scores([(t, spans, found) for t, spans, _, found in runs])
    truths = sum(len(spans) for _, spans, _, _ in runs)
    print(f"  continuous (c0, {truths} gestures in {len(users)} streams): precision {precision:.3f}, "
          f"recall {recall:.3f}, F1 {f1:.3f} (target F1 ≥ 0.90; tokens alone: F1 "
          f"{_scores([(t, spans, found) for t, spans, found, _ in runs])[2]:.3f})")


def _scores(runs) -> tuple[float, float, float]:
    """Precision, recall and F1 of detections: one counts when its class is right and it
    overlaps a true gesture not yet counted."""
    tp = detections = truths = 0
    for t, spans, segments in runs:
        used = set()
        for s in segments:
            a, b = t[s.start], t[min(s.end, len(t) - 1)]
            hit = next((k for k, (g, t0, t1) in enumerate(spans)
                        if k not in used and g == s.action and a < t1 and b > t0), None)
            if hit is not None:
                used.add(hit)
                tp += 1
        detections += len(segments)
        truths += len(spans)
    precision, recall = tp / max(detections, 1), tp / max(truths, 1)
    return precision, recall, 2 * precision * recall / max(precision + recall, 1e-9)

if __name__ == "__main__":
    main()
