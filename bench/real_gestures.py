"""Do the tokens carry the gesture? Nearest-token-string classification on real Vive data.

For each user of ../shared/data/vive-gestures: examples 0–2 of every gesture are templates,
examples 3 and 4 are classified by the nearest template under the normalised edit distance
between compacted token strings (``lev(a, b) / max(|a|, |b|)``). Track c0 (the right hand),
default Segmenter parameters. Baseline in the same run: the same classifier on a token-free
representation — each recording's c0 path resampled to 16 points, centred, as a string of
16 coarse world-direction symbols (the sign pattern of each step) — and chance (1/11).
"""

from collections import Counter, defaultdict
from pathlib import Path

import numpy as np

from doodle.input.csvimport import read_csv
from doodle.input.segmenter import SegmenterParams, tokenize_doodle

ROOT = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "vive-gestures"


def levenshtein(a, b) -> int:
    row = list(range(len(b) + 1))
    for i, x in enumerate(a, 1):
        prev, row[0] = row[0], i
        for j, y in enumerate(b, 1):
            prev, row[j] = row[j], min(row[j] + 1, row[j - 1] + 1, prev + (x != y))
    return row[-1]


def distance(a, b) -> float:
    return levenshtein(a, b) / max(len(a), len(b), 1)


def direction_string(p: np.ndarray, points: int = 16) -> list[str]:
    s = np.concatenate([[0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))])
    u = np.linspace(0, s[-1], points + 1)
    r = np.column_stack([np.interp(u, s, p[:, k]) for k in range(3)])
    d = np.diff(r, axis=0)
    big = np.abs(d) >= 0.5 * np.abs(d).max(axis=1, keepdims=True)
    return ["".join("+" if x > 0 else "-" if on else "0" for x, on in zip(row, m)) for row, m in zip(d, big)]


def classify(data, key):
    correct, total, per_user = 0, 0, {}
    confusion = Counter()
    for user, gestures in sorted(data.items()):
        templates = [(g, ex[key]) for g, exs in gestures.items() for ex in exs[:3]]
        ok = n = 0
        for g, exs in gestures.items():
            for ex in exs[3:5]:
                guess = min(templates, key=lambda tpl: distance(ex[key], tpl[1]))[0]
                ok += guess == g
                n += 1
                confusion[(g, guess)] += 1
        per_user[user] = ok / n
        correct, total = correct + ok, total + n
    return correct / total, per_user, total, confusion


def main() -> None:
    files = sorted(ROOT.glob("*/*/*.csv"))
    if not files:
        print(f"Real gestures: no data under {ROOT}")
        return
    data = defaultdict(lambda: defaultdict(list))
    loaded = tokenised = 0
    lengths = []
    for path in files:
        doodle = read_csv(path, convention="unity")
        loaded += 1
        c0 = doodle.select(["c0"])
        names = [k.name for k in tokenize_doodle(c0)["c0"]]
        tokenised += 1
        lengths.append(len(names))
        savgol = [k.name for k in tokenize_doodle(c0, SegmenterParams(smoothing="savgol"))["c0"]]
        user, gesture = path.parts[-3], path.parts[-2]
        data[user][gesture].append({"tokens": names, "savgol": savgol, "path": direction_string(doodle.track("c0").p)})
    print(f"Real Vive gestures ({ROOT})")
    print(f"  files loaded: {loaded}/{len(files)}, c0 tokenised: {tokenised}/{len(files)}; "
          f"c0 tokens per recording: median {int(np.median(lengths))}, range {min(lengths)}–{max(lengths)}")
    acc, per_user, total, confusion = classify(data, "tokens")
    base, base_users, _, _ = classify(data, "path")
    sg, _, _, _ = classify(data, "savgol")
    print(f"  nearest token string, c0, 3 templates per gesture per user: accuracy {acc:.3f} over {total} "
          f"examples (target ≥ 0.80)")
    print("    per user: " + ", ".join(f"{u} {a:.2f}" for u, a in per_user.items()))
    print(f"  the same with Savitzky–Golay smoothing instead of Laplacian: accuracy {sg:.3f}")
    print(f"  baseline, 16-step world-direction string of the path: accuracy {base:.3f}; chance {1 / 11:.3f}")
    errors = sorted(((n, g, h) for (g, h), n in confusion.items() if g != h), reverse=True)[:5]
    if errors:
        print("  most frequent confusions: " + "; ".join(f"{g} → {h} ×{n}" for n, g, h in errors))


if __name__ == "__main__":
    main()
