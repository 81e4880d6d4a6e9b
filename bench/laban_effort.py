"""Laban effort recognition (§4.4): classifying one segment (target ≤ 5 ms) beside the
Naive Bayes classifier's cost; training the default models; accuracy of the shipped model on
generated held-out performers per Factor, State and Drive for the three methods (thesis
anchors beside them); agreement of the qualities given to repetitions of the same gesture by
the same user on the real Vive recordings, beside chance agreement; and the cross-procedure
evaluation of Time and Weight on effort applied to real neutral motion capture (train on one
procedure, test on the other, per size and tracking rate, beside the thesis's figures)."""

import collections
import time
from pathlib import Path

import numpy as np

from bench.timing import best_of
from laban.classify import bayes_drive, quality
from laban.features import summary
from laban.models import load
from laban.train import evaluate, generated, train, train_default

VIVE = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "vive-gestures"


def main() -> None:
    model = load()
    curves = generated("test")
    c = next(c for c in curves if len(c.t) >= 270)
    seg = 270  # a 3 s segment at 90 Hz
    t, p, q = c.t[:seg], c.p[:seg], c.q[:seg]
    hmm = best_of(lambda: quality(model, t, p, q), 20, warm=True)
    nb = best_of(lambda: bayes_drive(model, summary(t, p, q)[None]), 20, warm=True)
    print(f"Laban effort: classifying one {t[-1] - t[0]:.1f} s segment ({seg} samples)")
    print(f"  Drive HMM (features + 8 models)  {hmm * 1000:6.2f} ms   (target ≤ 5 ms)")
    print(f"  baseline: Naive Bayes            {nb * 1000:6.2f} ms")

    report = evaluate(model, curves)["methods"]
    print(f"Accuracy on {len(curves)} generated curves of 3 held-out performers (chance: factor 0.5, State 0.25, "
          "Drive 0.125)")
    print(f"  {'method':<12} {'space':>6} {'time':>6} {'weight':>6} {'state':>6} {'drive':>6}")
    for method, r in report.items():
        print(f"  {method:<12} " + " ".join(f"{r[k]:6.3f}" for k in ("space", "time", "weight", "state", "drive")))
    print("  thesis (recorded curves): Drive HMM drive 0.44, State 0.61-0.63, time > 0.85; Element HMM drive 0.25; "
          "NB drive 0.35 (NB States 0.35 vs HMM 0.43 on action segments)")

    start = time.perf_counter()
    train_default()
    print(f"Training the default models (384 curves, ×16 sub-sampling, 14 HMMs + 3 NB): "
          f"{time.perf_counter() - start:.1f} s")

    print("Feature sets of Table 4.3 (HMMs trained with ×4 sub-sampling; same held-out curves): drive / state")
    train_curves, held = generated("train"), generated("calibrate")
    thesis = {1: "thesis DHMM 0.249, CHMM 0.185", 2: "thesis DHMM 0.426 / 0.63, CHMM 0.251 / 0.62",
              3: "thesis DHMM 0.439 / 0.61, CHMM 0.25 / 0.58"}
    for k in (1, 2, 3):
        sets = ("euclidean", "affine", "moving")[:k]
        r = evaluate(train(train_curves, held, sets=sets, augment=4), curves)["methods"]
        print(f"  {' + '.join(sets):<28} Drive HMM {r['drive_hmm']['drive']:.3f} / {r['drive_hmm']['state']:.3f}   "
              f"Element HMM {r['element_hmm']['drive']:.3f} / {r['element_hmm']['state']:.3f}   ({thesis[k]})")

    _real(model)
    print()
    cross_procedure()


def cross_procedure() -> None:
    """``python -m bench.laban_effort``'s last table: see :mod:`doodle.app.effort_corpus`."""
    from doodle.app.effort_corpus import HELD_OUT, MOCAP, cross_procedure as run, held_out, held_out_title, proxy_table, reliability, \
        styled_proxy, table

    if not MOCAP.is_dir():
        print(f"Cross-procedure Effort accuracy: motion capture not found under {MOCAP}")
        return
    start = time.perf_counter()
    rep = run(MOCAP)
    print("\n".join(table(rep)))
    rel = reliability(rep)
    print(f"  calibration (cross-procedure runs): expected calibration error Time {rel['time']['ece']:.3f}, "
          f"Weight {rel['weight']['ece']:.3f}  ({time.perf_counter() - start:.0f} s)")
    for run in rep["runs"]:
        print(f"  {run['name']}: chose Time {run['chosen']['time']}; Weight {run['chosen']['weight']}")
    if HELD_OUT.is_dir():
        start = time.perf_counter()
        rep = held_out(MOCAP)
        print("\n".join(table(rep, held_out_title(rep))))
        print(f"  ({time.perf_counter() - start:.0f} s)")
    model = load()
    print("\n".join(proxy_table(styled_proxy(model.factors, model.threshold, root=MOCAP))))


def _real(model) -> None:
    files = sorted(VIVE.glob("*/*/*.csv"))
    if not files:
        print(f"Real repetitions: recordings not found under {VIVE}")
        return
    from doodle.input.csvimport import read_csv

    by_gesture = collections.defaultdict(list)
    for path in files:
        tr = read_csv(path, convention="unity").tracks[0]
        by_gesture[(path.parts[-3], path.parts[-2])].append(quality(model, tr.t, tr.p, tr.q))
    print(f"Real repetitions ({len(files)} recordings, {len(by_gesture)} user × gesture groups, c0, whole take): "
          "pairs of repetitions given the same label")
    for key, name in (("p_sudden", "Time (Sudden/Sustained)"), ("p_strong", "Weight (Strong/Light)")):
        labels = [[getattr(q, key) > 0.5 for q in qs] for qs in by_gesture.values()]
        pairs = [a == b for ls in labels for i, a in enumerate(ls) for b in ls[i + 1:]]
        share = float(np.mean([x for ls in labels for x in ls]))
        chance = share**2 + (1 - share) ** 2
        print(f"  {name:<24} agreement {np.mean(pairs):.3f}   (chance with the same shares {chance:.3f}; "
              f"{share:.0%} {'Sudden' if key == 'p_sudden' else 'Strong'})")


if __name__ == "__main__":
    main()
