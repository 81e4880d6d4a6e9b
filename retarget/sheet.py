"""Contact sheets of clips: a PNG grid of stick figures, one row per clip.

``contact_sheet(motions, path, frames_per_clip=6)`` draws, for each clip, evenly spaced
frames (or the frames given per clip in ``frames``) as stick figures. Each cell shows two
projections side by side: the side view (z forward to the right, y up) and the front view
(the figure faces the viewer, so its left, +x, appears on the viewer's
right). Left limbs are blue, right limbs red, the spine
black; the ground line is grey. Needs matplotlib (Agg backend).

Command line: ``doodle library sheet [-o out.png] [--library DIR]`` draws every clip of a
library at its stage ends.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from retarget.skeleton import Motion, end_site_positions, forward_kinematics

LEFT, RIGHT, MID = "#1f5fd6", "#d62728", "#222222"


def _side(name: str) -> str:
    n = name.lower()
    if n.startswith("left") or n.endswith("_l") or n.startswith("l_"):
        return LEFT
    if n.startswith("right") or n.endswith("_r") or n.startswith("r_"):
        return RIGHT
    return MID


def contact_sheet(motions: dict, path, frames_per_clip: int = 6, frames: dict | None = None,
                  views: tuple[str, ...] = ("side", "front"), cell: float = 1.3, labels: dict | None = None,
                  wrap: int | None = None) -> Path:
    """Render the clips of ``motions`` (name → Motion) as a grid PNG at ``path``: a row of
    cells per clip (``wrap`` cells a row at most, continuing on the next), each titled with
    its frame number or its ``labels[name][k]``."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = []  # (name, frames of the row, their titles)
    for name, m in motions.items():
        picks = list((frames or {}).get(name) or np.linspace(0, m.frames - 1, frames_per_clip).round().astype(int))
        picks = [min(max(int(f), 0), m.frames - 1) for f in picks]
        titles = list((labels or {}).get(name) or [str(f) for f in picks])
        step = wrap or max(len(picks), 1)
        for k in range(0, max(len(picks), 1), step):
            rows.append((name if k == 0 else "", name, picks[k:k + step], titles[k:k + step]))
    cols = max(frames_per_clip if not frames else 0, max((len(r[2]) for r in rows), default=0))
    nv = len(views)
    tall = 1.25 if labels else 1.0
    fig, axes = plt.subplots(len(rows), cols * nv, figsize=(cols * nv * cell * 0.75, len(rows) * cell * tall),
                             squeeze=False)
    for r, (shown, name, picks, titles) in enumerate(rows):
        m: Motion = motions[name]
        world = forward_kinematics(m)
        pos = world[0]
        ends = end_site_positions(m, world)
        sk = m.skeleton
        top = max(1.95, max([pos[..., 1].max()] + [e[:, 1].max() for e in ends.values()]) + 0.08)
        for c in range(cols):
            for k, view in enumerate(views):
                ax = axes[r, c * nv + k]
                ax.set_xticks([]); ax.set_yticks([])
                for s in ax.spines.values():
                    s.set_color("#dddddd")
                if c >= len(picks):
                    ax.axis("off")
                    continue
                f = picks[c]
                h = 2 if view == "side" else 0  # horizontal axis: z (side) or x (front)
                sign = 1.0  # front view: the figure faces us, so its left (+x) is on our right
                cx = pos[f, 0, h]
                P = lambda p: (sign * (p[h] - cx), p[1])  # noqa: E731
                ax.axhline(0, color="#999999", lw=1)
                order = sorted(range(1, len(sk)), key=lambda j: -pos[f, j, 0] if view == "side" else pos[f, j, 2])  # far first
                for j in order:  # far side first
                    p = sk.parents[j]
                    a, b = P(pos[f, p]), P(pos[f, j])
                    ax.plot([a[0], b[0]], [a[1], b[1]], color=_side(sk.names[j]), lw=1.6, solid_capstyle="round")
                for j, e in ends.items():
                    a, b = P(pos[f, j]), P(e[f])
                    ax.plot([a[0], b[0]], [a[1], b[1]], color=_side(sk.names[j]), lw=1.6)
                head = sk.names.index("Head") if "Head" in sk.names else None
                if head is not None:
                    hp = P(pos[f, head] + 0.5 * (ends.get(head, pos[:, head])[f] - pos[f, head]))
                    ax.plot(*hp, "o", color=MID, ms=5, mfc="white")
                ax.set_xlim(-1.0, 1.0); ax.set_ylim(-0.05, top)
                ax.set_aspect("equal")
                if k == 0:
                    ax.set_title(titles[c], fontsize=7 if labels else 6, pad=1, loc="left" if labels else "center")
        axes[r, 0].set_ylabel(shown, fontsize=8, rotation=0, ha="right", va="center")
    fig.subplots_adjust(left=0.09, right=0.995, top=0.995, bottom=0.005, wspace=0.02, hspace=0.12)
    path = Path(path)
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return path
