"""Previews of a compiled animation: a plan view of the paths and a strip of key poses.

* ``plan.png`` — seen from above (forward, +z, up the page; the performer's left, +x, on
  the left): each track's root path,
  coloured by action segment, over the projected doodle (grey) it was made from.
* ``keyframes.png`` — per track, the character at the middle of every segment (side and
  front views), labelled with the frame; see :func:`retarget.sheet.contact_sheet`.

Needs matplotlib (Agg backend); files are written to a temporary name and renamed.
"""

from __future__ import annotations

from pathlib import Path

from doodle.core.files import atomic_path
from retarget.sheet import contact_sheet
from retarget.skeleton import forward_kinematics


def atomic_png(path: Path, draw) -> None:
    """Call ``draw(temporary_name)`` and rename the file to ``path`` when it succeeded."""
    with atomic_path(path) as tmp:
        draw(tmp)


def plan_view(results, projected: dict, path) -> Path:
    """Root paths by segment over each track's projected doodle (``projected[track]`` (n, 3))."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    path = Path(path)
    fig, ax = plt.subplots(figsize=(6, 6))
    colours = plt.get_cmap("tab20")
    names = sorted({s.action for r in results for s in r.segments})
    for r in results:
        doodle = projected[r.track]
        ax.plot(doodle[:, 0], doodle[:, 2], color="#bbbbbb", lw=1, ls="--")
        hips = forward_kinematics(r.motion)[0][:, r.roles["pelvis"]]
        for k, s in enumerate(r.segments):
            a, b = r.frame_ranges[k]
            colour = colours(names.index(s.action) % 20)
            ax.plot(hips[a:b + 1, 0], hips[a:b + 1, 2], color=colour, lw=2.5,
                    label=s.action if s.action not in ax.get_legend_handles_labels()[1] else None)
        ax.plot(*hips[0, [0, 2]], "o", color="black", ms=5)
        ax.annotate(r.track, hips[0, [0, 2]], textcoords="offset points", xytext=(4, 4), fontsize=8)
    ax.set_aspect("equal")
    ax.invert_xaxis()  # seen from above with forward up the page, the performer's left (+x) is on the left
    ax.set_xlabel("x (m, +x is the performer's left)")
    ax.set_ylabel("z (m, forward)")
    ax.legend(fontsize=7, loc="best")
    ax.grid(alpha=0.3)
    fig.tight_layout()
    atomic_png(path, lambda name: fig.savefig(name, dpi=100))
    plt.close(fig)
    return path


def keyframes(results, path) -> Path:
    """The character at the middle of each segment — a grid, rows of six per track, each
    cell titled with the segment's action and time."""
    path = Path(path)
    motions = {r.track: r.motion for r in results}
    frames = {r.track: [int((a + b) // 2) for a, b in r.frame_ranges] for r in results}
    labels = {r.track: [f"{s.action} {f * r.motion.frame_time:.2f} s" for s, f in zip(r.segments, frames[r.track])]
              for r in results}
    atomic_png(path, lambda name: contact_sheet(motions, name, frames=frames, labels=labels, wrap=6))
    return path


def compare_picture(neutral, styled, effectors: list[int], path, title: str = "", notes: list[str] | None = None) -> Path:
    """Fig. 5.13-style comparison: neutral and stylised end-effector paths (side view, z
    forward, y up) and the first effector's speed over time — as the signature measures read
    it (``retarget.effort_signature.speed_profile``), its execution (speed at least half its
    peak) shaded; ``notes``: lines written on the speed plot (the signature measures)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    path = Path(path)
    fig, axes = plt.subplots(1, 3, figsize=(12, 4))
    for ax, motion, label in ((axes[0], neutral, "neutral"), (axes[1], styled, title or "stylised")):
        world = forward_kinematics(motion)[0]
        for j in effectors:
            ax.plot(world[:, j, 2], world[:, j, 1], lw=1.5, label=motion.skeleton.names[j])
        ax.set_title(label)
        ax.set_aspect("equal")
        ax.set_xlabel("z (m)")
        ax.set_ylabel("y (m)")
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=7)
    from retarget.effort_signature import RATE, burst, speed_profile

    for motion, style, colour, label in ((neutral, "-", "C0", "neutral"), (styled, "--", "C3", "stylised")):
        tt, speed = speed_profile(motion, effectors[0])  # the curve the signature measures read
        a, _, b = burst(speed)
        axes[2].plot(tt, speed, style, color=colour, label=label)
        axes[2].axvspan(a / RATE, b / RATE, color=colour, alpha=0.12, lw=0)  # the execution: speed ≥ half its peak
    axes[2].set_xlabel("time (s)")
    axes[2].set_ylabel(f"{neutral.skeleton.names[effectors[0]]} speed (m/s)")
    axes[2].legend(fontsize=7)
    axes[2].grid(alpha=0.3)
    if notes:
        axes[2].text(0.98, 0.97, "\n".join(notes), transform=axes[2].transAxes, ha="right", va="top", fontsize=7,
                     bbox={"facecolor": "white", "alpha": 0.8, "edgecolor": "0.7"})
    fig.tight_layout()
    atomic_png(path, lambda name: fig.savefig(name, dpi=90))
    plt.close(fig)
    return path
