"""Pictures of an evaluation: confusion matrices (rows: truth, columns: predicted) and the
reliability diagram of the Time and Weight confidences."""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np


def confusion_png(matrix, labels: list[str], path, title: str) -> Path:
    """A confusion matrix drawn as a PNG (counts and row shares), written atomically."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    m = np.asarray(matrix, dtype=float)
    share = m / np.maximum(m.sum(axis=1, keepdims=True), 1)
    fig, ax = plt.subplots(figsize=(max(5.0, 1.0 + 0.75 * len(labels)), max(4.5, 0.8 + 0.7 * len(labels))))
    ax.imshow(share, cmap="Blues", vmin=0, vmax=1)
    ax.set_xticks(range(len(labels)), labels, rotation=45, ha="right")
    ax.set_yticks(range(len(labels)), labels)
    ax.set_xlabel("predicted")
    ax.set_ylabel("truth")
    for i in range(len(labels)):
        for j in range(len(labels)):
            ax.text(j, i, f"{int(m[i, j])}", ha="center", va="center", color="white" if share[i, j] > 0.5 else "black")
    accuracy = np.trace(m) / max(m.sum(), 1)
    ax.set_title(f"{title}\naccuracy {accuracy:.3f}")
    return _save(fig, path)


def reliability_png(reliability: dict, path, title: str | None = None) -> Path:
    """A reliability diagram: per confidence bin, the share of decisions that were right
    against the confidence they were given (the diagonal is perfect calibration), for Time
    and Weight, with the bins' counts, under ``title``; written atomically."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(9.0, 4.2))
    for ax, factor in zip(axes, ("time", "weight")):
        r = reliability[factor]
        rows = [b for b in r["bins"] if b["n"]]
        conf = [b["confidence"] for b in rows]
        acc = [b["accuracy"] for b in rows]
        ax.plot([0.5, 1.0], [0.5, 1.0], color="grey", lw=1, ls="--", label="perfectly calibrated")
        ax.plot(conf, acc, "o-", color="tab:blue", label="decisions")
        for c, a, b in zip(conf, acc, rows):
            ax.annotate(str(b["n"]), (c, a), textcoords="offset points", xytext=(0, 6), ha="center", fontsize=7)
        ax.set_xlim(0.5, 1.0)
        ax.set_ylim(0.0, 1.02)
        ax.set_xlabel("confidence")
        ax.set_ylabel("share right")
        ax.set_title(f"{'Time' if factor == 'time' else 'Weight'}: ECE {r['ece']:.3f} ({r['n']} decisions)")
        ax.legend(loc="lower right", fontsize=8)
    if title:
        fig.suptitle(title, fontsize=9)
    return _save(fig, path)


def _save(fig, path) -> Path:
    """The figure as a PNG at ``path``, written atomically; the figure closed."""
    import matplotlib.pyplot as plt

    from doodle.core.files import atomic_write

    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, dpi=100, format="png")
    plt.close(fig)
    atomic_write(Path(path), buf.getvalue())
    return Path(path)
