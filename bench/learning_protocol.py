"""Learned gestures on the real Vive recordings, measured through the product path and
held out from every constant.

Protocol (the one someone with new users would run):

* **User-dependent.** Per user, a library is made with the function ``doodle learn`` uses
  (:func:`doodle.app.cli.learn.learn_action`, written and loaded as ``doodle recognize
  --library DIR --no-builtin`` loads it), every gesture learned from ex_0..ex_2 — on c0
  alone, and on c0+c1 as one two-handed action (``--tracks c0,c1``). ex_3 and ex_4 are
  recognised with :func:`grammar.recognizer.recognize` (what ``doodle recognize`` runs) and
  scored as ``recognize --json`` reports them: a recording's answer is the name of its
  longest non-unknown segment (a two-handed action's ``interaction``, which is its name);
  no such segment, or another name, is an error.
* **User-independent.** The same, each user's gestures learned from ex_0 of three other
  users (the next three in order: three examples, as a person would give; ``doodle learn``
  from four such different people can find no token all share and refuses).
* **Baseline.** Direction-vector DTW 1-NN (each track's path resampled to 32 points by arc
  length, unit step directions, both tracks side by side) with the same training examples.
* **Continuous.** Per user, the held-out recordings (ex_3, ex_4 of every gesture) in a
  shuffled order, each moved to start where the previous ended, joined by an idle stretch
  (a still pause with tracking noise and a short turn of the wrist) — or by nothing at all
  (back to back); recognised whole; a detection counts when its name is right and it
  overlaps a true gesture not yet counted (precision, recall, F1).
* **Constants held out.** Each constant the recogniser keeps (:data:`grammar.refiner.WEIGHT`,
  :data:`grammar.shapes.SPREAD`, :data:`grammar.refiner.TEMPO`, :data:`grammar.shapes.TURN` — which a
  library's own examples may overrule, :func:`grammar.shapes.choose_turn` —, :data:`grammar.shapes.PACE`) is swept over a
  grid; for each user the value best on the other four users is taken and that user's
  figure at it reported (leave one user out), beside the product's value on all five
  (in-sample). Nothing is chosen on the user it is reported for.
* **Every split** (``--all-splits``, about 40 minutes): the bench's single split is a small
  sample (one test is 0.009 of a user-independent figure), so with the product's constants
  the same is measured on every split — user-dependent: every choice of three training
  examples of the five (ten per user), the other two tested; user-independent: ex_k of the
  next three users for k = 0..4, all five of the user's examples tested; continuous: one
  stream per user-dependent split of its held-out recordings. The constants are not held out
  there (they were chosen on these users); only the training examples are. With
  ``--all-splits --builtin``, the same with the built-in actions loaded beside the learned ones.
"""

from __future__ import annotations

import tempfile
import time
from collections import defaultdict
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "vive-gestures"
SETTINGS = (("c0",), ("c0", "c1"))
GRID = {"WEIGHT": (8.0, 31.0, 62.0, 125.0), "SPREAD": (0.0, 0.95, 0.99),
        "TEMPO": (1.25, 1.5, 2.0, np.inf), "TURN": (0.25, 0.5, 1.0), "PACE": (0.0, 1.0, 2.0, 4.0)}  # swept by `make bench` (the product's
#                                                                       values among them)
FULL_GRID = {"WEIGHT": (0.0, 8.0, 31.0, 62.0, 125.0), "SPREAD": (0.0, 0.9, 0.95, 0.99),
             "TEMPO": (1.1, 1.25, 1.5, 2.0, 3.0, np.inf), "TURN": (0.0, 0.25, 0.5, 1.0),
             "PACE": (0.0, 0.5, 1.0, 2.0, 4.0)}  # with --full


def load(root: Path = ROOT) -> dict:
    from doodle.input.csvimport import read_csv

    data = defaultdict(lambda: defaultdict(list))
    for path in sorted(root.glob("*/*/*.csv")):
        data[path.parts[-3]][path.parts[-2]].append(read_csv(path, convention="unity"))
    return {u: dict(g) for u, g in data.items()}


def make_library(folder: Path, examples: dict, tracks) -> Path:
    """A user library in ``folder`` with every gesture of ``{name: [doodles]}`` learned
    on ``tracks``, as ``doodle learn NAME … --tracks`` makes it (one action per gesture)."""
    from doodle.app.cli.learn import learn_action
    from doodle.core.files import atomic_write
    from doodle.input.segmenter import SegmenterParams
    from grammar.shapes import save_paths
    from library.manifest import Library, format_library, manifest_path

    folder.mkdir(parents=True, exist_ok=True)
    (folder / "shapes").mkdir(exist_ok=True)
    library = Library(folder.name, (), str(manifest_path(folder)))
    for name, doodles in examples.items():
        library, files, _, _ = learn_action(library, name, doodles, list(tracks), SegmenterParams(), folder)
        for file, shape in files.items():
            save_paths(folder / "shapes" / file, *shape)
    atomic_write(manifest_path(folder), [format_library(library, folder.resolve())])
    return folder


def learning_times(data, users, classes) -> list[float]:
    """Seconds :func:`doodle.app.cli.learn.learn_action` takes (what ``doodle learn`` runs
    before it writes) per gesture, user and controller, from ex_0..ex_2: the median of three
    runs each, so a moment's load on a shared machine does not count as the learning's."""
    from doodle.app.cli.learn import learn_action
    from doodle.input.segmenter import SegmenterParams
    from library.manifest import Library

    out = []
    with tempfile.TemporaryDirectory() as tmp:
        for user in users:
            for g in classes:
                for track in ("c0", "c1"):
                    runs = []
                    for _ in range(3):
                        start = time.perf_counter()
                        learn_action(Library("t", (), ""), g, data[user][g][:3], [track], SegmenterParams(), Path(tmp))
                        runs.append(time.perf_counter() - start)
                    out.append(float(np.median(runs)))
    return out


def answers(doodle, compiled, tracks) -> list[tuple[str, int, int]]:
    """What ``recognize --json`` reports of a doodle, as (name, start, end) samples of its
    named segments on the first track (a two-handed action's name is its ``interaction``)."""
    from grammar.contexter import InteractionSegment
    from grammar.recognizer import recognize

    result = recognize(doodle.select(list(tracks)), compiled)
    _, segs = result[tracks[0]]
    return [((s.interaction if isinstance(s, InteractionSegment) else s.action), s.start, s.end)
            for s in segs if s.action != "unknown"]


def answer(doodle, compiled, tracks) -> str:
    named = answers(doodle, compiled, tracks)
    return max(named, key=lambda a: a[2] - a[1])[0] if named else "unknown"


def directions(d, tracks, points=32):
    """The baseline's representation: unit step directions of each track resampled by arc length."""
    cols = []
    for tr in tracks:
        p = d.track(tr).p
        s = np.concatenate([[0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))])
        u = np.linspace(0, s[-1], points)
        v = np.diff(np.column_stack([np.interp(u, s, p[:, k]) for k in range(3)]), axis=0)
        cols.append(v / np.maximum(np.linalg.norm(v, axis=1, keepdims=True), 1e-9))
    return np.hstack(cols)


def baseline(train: dict, tests: list, tracks) -> list[str]:
    from grammar.shapes import dtw_costs

    labels = [g for g, ds in train.items() for _ in ds]
    templates = np.array([directions(d, tracks) for ds in train.values() for d in ds])
    return [labels[int(np.argmin(dtw_costs(directions(d, tracks), templates)))] for d in tests]


def stream(pieces, rng, idle: bool, rate: float = 90.0):
    """Recordings ``[(name, doodle)]`` joined into one doodle (shuffled; each moved to start
    where the previous ended, per track), with idle stretches between them or back to
    back; and the true spans ``[(name, t0, t1)]``."""
    from doodle.core.model import Doodle, Track

    names = pieces[0][1].names
    t_parts, spans = [], []
    parts = {n: ([], []) for n in names}
    clock = 0.0
    where = {n: np.zeros(3) for n in names}
    q_last = {n: np.array([0.0, 0.0, 0.0, 1.0]) for n in names}
    for k in rng.permutation(len(pieces)):
        g, d = pieces[k]
        if idle:
            n_pause, n_move = int(1.0 * rate), int(0.4 * rate)
            t_parts.append(clock + np.arange(n_pause + n_move) / rate)
            w = (0.5 - 0.5 * np.cos(np.linspace(0, np.pi, n_move)))[:, None]
            for n in names:
                tr = d.track(n)
                target = tr.q[0] * np.sign(np.dot(tr.q[0], q_last[n]) or 1.0)
                qm = (1 - w) * q_last[n] + w * target
                parts[n][0].append(np.concatenate([where[n] + rng.normal(0, 3e-4, (n_pause, 3)),
                                                   np.repeat(where[n][None], n_move, 0)]))
                parts[n][1].append(np.concatenate([np.tile(q_last[n], (n_pause, 1)),
                                                   qm / np.linalg.norm(qm, axis=1, keepdims=True)]))
            clock += (n_pause + n_move) / rate
        t = d.t - d.t[0]
        t_parts.append(clock + t)
        for n in names:
            tr = d.track(n)
            shift = where[n] - tr.p[0]
            parts[n][0].append(tr.p + shift)
            parts[n][1].append(tr.q)
            where[n], q_last[n] = tr.p[-1] + shift, tr.q[-1]
        spans.append((g, clock, clock + t[-1]))
        clock += t[-1] + 1.0 / rate
    t = np.concatenate(t_parts)
    tracks = tuple(Track(n, t, np.concatenate(parts[n][0]), np.concatenate(parts[n][1]), np.ones(len(t), dtype=bool))
                   for n in names)
    return Doodle(tracks, rate), spans


def stream_counts(doodle, spans, found) -> tuple[int, int, int]:
    """(true positives, detections, truths): a detection counts when its name is right and
    it overlaps a true gesture not yet counted. Idle (the built-in pause, when the built-in
    actions are loaded) is not a detection: the stream's idle stretches are pauses."""
    t = doodle.t
    found = [f for f in found if f[0] != "Idle"]
    used, tp = set(), 0
    for name, a, b in found:
        t0, t1 = t[a], t[min(b, len(t) - 1)]
        hit = next((k for k, (g, s0, s1) in enumerate(spans) if k not in used and g == name and t0 < s1 and t1 > s0),
                   None)
        if hit is not None:
            used.add(hit)
            tp += 1
    return tp, len(found), len(spans)


def f1(counts) -> float:
    tp, det, truth = (sum(c[k] for c in counts) for k in range(3))
    p, r = tp / max(det, 1), tp / max(truth, 1)
    return 2 * p * r / max(p + r, 1e-9)


def evaluate(data, users, classes, folders, streams, builtin: bool = False) -> dict:
    """Per (metric, user): the figure with the recogniser's constants as they are now.
    Metrics: ("dep"|"indep", tracks) isolated accuracy; ("stream", idle, tracks) counts.
    With ``builtin``, the built-in actions are loaded beside the learned ones (``doodle
    recognize --library DIR`` without ``--no-builtin``)."""
    from grammar.recognizer import load_actions

    out = {}
    for tracks in SETTINGS:
        for kind in ("dep", "indep"):
            for user in users:
                compiled = load_actions(folders[(kind, user, tracks)], builtin)
                right = [answer(d, compiled, tracks) == g for g in classes for d in data[user][g][3:5]]
                out[(kind, tracks), user] = float(np.mean(right))
                if kind == "dep":
                    for idle in (True, False):
                        doodle, spans = streams[(user, idle)]
                        out[("stream", idle, tracks), user] = stream_counts(doodle, spans,
                                                                            answers(doodle, compiled, tracks))
    return out


def main(quick: bool = False, full: bool = False) -> None:
    from grammar import refiner, shapes

    home = {"WEIGHT": refiner, "SPREAD": shapes, "TEMPO": refiner, "TURN": shapes, "PACE": shapes}  # where each is

    global GRID
    if full:
        GRID = FULL_GRID

    if not sorted(ROOT.glob("*/*/*.csv")):
        print(f"Learned gestures, product path: no data under {ROOT}")
        return
    began = time.perf_counter()
    data = load()
    users = sorted(data)
    classes = sorted(data[users[0]])
    print(f"Learned gestures through `doodle learn` / `doodle recognize` ({len(users)} users × {len(classes)} "
          "gestures; learn ex_0..2, recognise ex_3, ex_4; unknown counts as wrong)")
    rng = np.random.default_rng(0)
    streams = {(u, idle): stream([(g, d) for g in classes for d in data[u][g][3:5]], rng, idle)
               for u in users for idle in (True, False)}
    with tempfile.TemporaryDirectory() as tmp:
        folders, took = {}, []
        for tracks in SETTINGS:
            for user in users:
                start = time.perf_counter()
                folders[("dep", user, tracks)] = make_library(Path(tmp) / f"dep-{user}-{len(tracks)}",
                                                              {g: data[user][g][:3] for g in classes}, tracks)
                took.append((time.perf_counter() - start) / len(classes))
                others = _others(users, user)
                folders[("indep", user, tracks)] = make_library(
                    Path(tmp) / f"indep-{user}-{len(tracks)}",
                    {g: [data[u][g][0] for u in others] for g in classes}, tracks)
        each = learning_times(data, users, classes)
        print(f"  learning one action from 3 examples (one controller, with its shapes; {len(each)} actions): "
              f"mean {np.mean(each) * 1000:.0f} ms, max {np.max(each) * 1000:.0f} ms (target max ≤ 100 ms); "
              f"a whole library per gesture, both settings: mean {np.mean(took) * 1000:.0f} ms")
        product = {name: getattr(home[name], name) for name in GRID}
        sweeps = {}
        for name, values in GRID.items():
            for v in (values if not quick else ()):
                if v == product[name] and "figures" in sweeps:
                    sweeps[(name, v)] = sweeps["figures"]
                    continue
                setattr(home[name], name, v)
                try:
                    sweeps[(name, v)] = evaluate(data, users, classes, folders, streams)
                finally:
                    setattr(home[name], name, product[name])
                if v == product[name]:
                    sweeps["figures"] = sweeps[(name, v)]
            if quick:
                break
        figures = sweeps.get("figures") or evaluate(data, users, classes, folders, streams)
        beside = evaluate(data, users, classes, folders, streams, builtin=True)
        base = {}
        for tracks in SETTINGS:
            for user in users:
                tests = [d for g in classes for d in data[user][g][3:5]]
                truth = [g for g in classes for _ in data[user][g][3:5]]
                others = _others(users, user)
                dep = baseline({g: data[user][g][:3] for g in classes}, tests, tracks)
                ind = baseline({g: [data[u][g][0] for u in others] for g in classes}, tests, tracks)
                base[("dep", tracks), user] = float(np.mean([a == b for a, b in zip(dep, truth)]))
                base[("indep", tracks), user] = float(np.mean([a == b for a, b in zip(ind, truth)]))
    _report(users, figures, base, sweeps, product)
    _report_beside(users, figures, beside)
    print(f"  ({time.perf_counter() - began:.0f} s)")


def _others(users, user, n=3):
    """The users whose examples teach ``user``'s gestures user-independently: the next ``n``."""
    k = users.index(user)
    return [users[(k + j) % len(users)] for j in range(1, n + 1)]


def _held_out(users, sweeps, name, metric, product):
    """Per user: the value of constant ``name`` best on the other users, and that user's figure at it."""
    values = [v for (n, v) in (k for k in sweeps if isinstance(k, tuple)) if n == name]
    out = {}
    for user in users:
        def on_others(v):
            figs = [sweeps[(name, v)][metric, u] for u in users if u != user]
            return f1(figs) if metric[0] == "stream" else float(np.mean(figs))

        best = max(values, key=lambda v: (round(on_others(v), 9), v == product[name]))
        out[user] = (best, sweeps[(name, best)][metric, user])
    return out


def _report(users, figures, base, sweeps, product) -> None:
    short = {u: u.replace("Sub_", "") for u in users}
    head = "  ".join(f"{short[u]:>5}" for u in users)
    for kind, label in (("dep", "user-dependent"), ("indep", "user-independent")):
        for tracks in SETTINGS:
            metric = (kind, tracks)
            print(f"  {label}, {'+'.join(tracks):<5}  accuracy {np.mean([figures[metric, u] for u in users]):.3f} "
                  f"(DTW 1-NN baseline {np.mean([base[metric, u] for u in users]):.3f})")
            print(f"      per user            {head}")
            print("      ours (in-sample)    " + "  ".join(f"{figures[metric, u]:5.3f}" for u in users))
            for name in GRID:
                if any(k[0] == name for k in sweeps if isinstance(k, tuple)):
                    held = _held_out(users, sweeps, name, metric, product)
                    print(f"      {name + ' held out':<18}  " + "  ".join(f"{held[u][1]:5.3f}" for u in users)
                          + f"  mean {np.mean([held[u][1] for u in users]):.3f}; chosen "
                          + ", ".join(f"{held[u][0]:g}" for u in users) + f" (product {product[name]:g})")
            print("      DTW 1-NN            " + "  ".join(f"{base[metric, u]:5.3f}" for u in users))
    for tracks in SETTINGS:
        for idle in (True, False):
            metric = ("stream", idle, tracks)
            counts = [figures[metric, u] for u in users]
            tp, det, truth = (sum(c[k] for c in counts) for k in range(3))
            print(f"  continuous, {'+'.join(tracks):<5} {'idle between' if idle else 'back to back'}: "
                  f"F1 {f1(counts):.3f} (precision {tp / max(det, 1):.3f}, recall {tp / max(truth, 1):.3f}, "
                  f"{truth} gestures in {len(users)} streams)")
            print("      per user F1 (in-sample) " + "  ".join(f"{f1([figures[metric, u]]):5.3f}" for u in users))
            for name in GRID:
                if any(k[0] == name for k in sweeps if isinstance(k, tuple)):
                    held = _held_out(users, sweeps, name, metric, product)
                    print(f"      {name + ' held out':<22}  " + "  ".join(f"{f1([held[u][1]]):5.3f}" for u in users)
                          + f"  F1 {f1([held[u][1] for u in users]):.3f}; chosen "
                          + ", ".join(f"{held[u][0]:g}" for u in users))


def _report_beside(users, figures, beside) -> None:
    """The same libraries read with the built-in actions beside the learned ones, as
    ``doodle recognize --library DIR`` loads them by default (in-sample constants)."""
    print("  with the built-in actions beside the learned ones (`doodle recognize --library DIR`, the default; "
          "in-sample constants):")
    for kind, label in (("dep", "user-dependent"), ("indep", "user-independent")):
        for tracks in SETTINGS:
            metric = (kind, tracks)
            print(f"      {label + ', ' + '+'.join(tracks):<28} accuracy "
                  f"{np.mean([beside[metric, u] for u in users]):.3f} "
                  f"(learned alone {np.mean([figures[metric, u] for u in users]):.3f}); per user "
                  + " ".join(f"{beside[metric, u]:.3f}" for u in users))
    for tracks in SETTINGS:
        for idle in (True, False):
            metric = ("stream", idle, tracks)
            print(f"      continuous, {'+'.join(tracks):<5} {'idle between' if idle else 'back to back':<12}   F1 "
                  f"{f1([beside[metric, u] for u in users]):.3f} "
                  f"(learned alone {f1([figures[metric, u] for u in users]):.3f})")


def all_splits(builtin: bool = False) -> dict:
    """The figures on every split, with the product's constants (see the module's
    docstring), beside DTW 1-NN on the same splits; printed per user, and returned as
    ``{(metric, user): [right or counts, …]}`` (metrics as :func:`evaluate`'s, plus
    ``("dtw", kind, tracks)``). With ``builtin`` (``--all-splits --builtin``) the built-in
    actions are loaded beside the learned ones, as ``doodle recognize --library DIR`` does."""
    import itertools

    from grammar.recognizer import load_actions

    if not sorted(ROOT.glob("*/*/*.csv")):
        print(f"Learned gestures, every split: no data under {ROOT}")
        return {}
    began = time.perf_counter()
    data = load()
    users = sorted(data)
    classes = sorted(data[users[0]])
    out = defaultdict(list)
    rng = np.random.default_rng(0)
    with tempfile.TemporaryDirectory() as tmp:
        for tracks in SETTINGS:
            for user in users:
                splits = [("dep", {g: [data[user][g][i] for i in train] for g in classes},
                           [(g, data[user][g][i]) for g in classes for i in range(5) if i not in train])
                          for train in itertools.combinations(range(5), 3)]
                splits += [("indep", {g: [data[u][g][k] for u in _others(users, user)] for g in classes},
                            [(g, d) for g in classes for d in data[user][g][:5]]) for k in range(5)]
                for n, (kind, train, tests) in enumerate(splits):
                    compiled = load_actions(make_library(Path(tmp) / f"{user}-{len(tracks)}-{n}", train, tracks),
                                            builtin)
                    out[(kind, tracks), user] += [answer(d, compiled, tracks) == g for g, d in tests]
                    out[("dtw", kind, tracks), user] += [a == g for (g, _), a in
                                                         zip(tests, baseline(train, [d for _, d in tests], tracks))]
                    if kind == "dep":
                        for idle in (True, False):
                            doodle, spans = stream(tests, rng, idle)
                            out[("stream", idle, tracks), user].append(
                                stream_counts(doodle, spans, answers(doodle, compiled, tracks)))
    short = "  ".join(f"{u.replace('Sub_', ''):>5}" for u in users)
    print(f"Learned gestures on every split, product constants (in-sample for them; {len(users)} users"
          + ("; the built-in actions loaded beside them)" if builtin else ")"))
    for kind, label in (("dep", "user-dependent, 10 splits"), ("indep", "user-independent, 5 splits")):
        for tracks in SETTINGS:
            ours, dtw = ([out[(m, user)] for user in users] for m in ((kind, tracks), ("dtw", kind, tracks)))
            print(f"  {label}, {'+'.join(tracks):<5} accuracy {np.mean(np.concatenate(ours)):.3f} "
                  f"(DTW 1-NN {np.mean(np.concatenate(dtw)):.3f}; {sum(map(len, ours))} tests)")
            print(f"      per user  {short}")
            print("      ours      " + "  ".join(f"{np.mean(o):5.3f}" for o in ours))
            print("      DTW 1-NN  " + "  ".join(f"{np.mean(o):5.3f}" for o in dtw))
    for tracks in SETTINGS:
        for idle in (True, False):
            counts = [c for user in users for c in out[("stream", idle, tracks), user]]
            print(f"  continuous, {'+'.join(tracks):<5} {'idle between' if idle else 'back to back'}: F1 {f1(counts):.3f} "
                  f"({len(counts)} streams); per user "
                  + "  ".join(f"{f1(out[('stream', idle, tracks), user]):5.3f}" for user in users))
    print(f"  ({time.perf_counter() - began:.0f} s)")
    return dict(out)


if __name__ == "__main__":
    import sys

    if "--all-splits" in sys.argv:
        all_splits(builtin="--builtin" in sys.argv)
    else:
        main(quick="--quick" in sys.argv, full="--full" in sys.argv)
