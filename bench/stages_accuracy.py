"""Automatic stage extraction (§5.3.2) against known stages: the keyed built-in clips and
hand-labelled real clips.

Built-in clips are keyframed with known stage ends (library.toml ``stages``). Real clips:
the Bandai clips of ``bench/stage_labels.toml`` (labelled by eye, see its header), when
``../shared/data/mocap`` is present; each labelled repetition is measured on its own frame
range, and the default extraction also end to end — its own split into repetitions
(:func:`retarget.analysis.repetitions`). The extractor's constants were chosen on the
``tune`` clips; the ``held-out`` ones only measure it. Printed: mean absolute error in frames
per stage end, and how many clips (repetitions) get all four ends within 3 frames, beside
the baseline of cutting the clip (repetition) in five equal parts.
"""

import tomllib
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from retarget.analysis import repetitions, section, stages
from retarget.bvh import read_bvh
from retarget.skeleton import Motion

LABELS = Path(__file__).with_name("stage_labels.toml")
MOCAP = Path(__file__).resolve().parents[2] / "shared" / "data" / "mocap"
METHODS = {"speed": "speed profile (default)", "keyframes": "optimal keyframe reduction (old default)",
           "extremes": "extreme poses (thesis 5.3.2)", "equal": "baseline, five equal parts"}


@dataclass(frozen=True)
class Labelled:
    """One hand-labelled clip: its file, split, note and repetitions
    (start, end, four stage ends)."""

    file: str
    split: str
    note: str
    reps: tuple[tuple[int, ...], ...]


def labels(path: Path = LABELS) -> list[Labelled]:
    data = tomllib.loads(path.read_text())
    return [Labelled(c["file"], c["split"], c.get("note", ""), tuple(tuple(r) for r in c["reps"]))
            for c in data["clip"]]


def ends_of(motion: Motion, method: str) -> np.ndarray:
    """The four stage ends a method finds (``"equal"``: the clip cut in five equal parts)."""
    if method == "equal":
        return np.round(np.arange(1, 5) * motion.frames / 5)
    found = stages(motion, method=method)
    return np.array([found.preparation, found.anticipation, found.execution, found.follow_through])


def real_errors(clips: list[Labelled], method: str, mocap: Path = MOCAP) -> np.ndarray:
    """(repetitions, 4) absolute errors, each labelled repetition measured on its own range."""
    out = []
    for clip in clips:
        motion = read_bvh(mocap / clip.file)
        for start, end, *keyed in clip.reps:
            out.append(np.abs(ends_of(section(motion, start, end), method) + start - np.array(keyed)))
    return np.array(out)


def split_errors(clips: list[Labelled], mocap: Path = MOCAP) -> tuple[np.ndarray, int, int]:
    """End to end: the default extraction on each repetition :func:`repetitions` finds,
    against the labelled one it overlaps most; returns the errors, the number of clips whose
    count of repetitions is right and the number of clips."""
    out, right = [], 0
    for clip in clips:
        motion = read_bvh(mocap / clip.file)
        found = repetitions(motion)
        right += len(found) == len(clip.reps)
        for start, end, *keyed in clip.reps:
            a, b = max(found, key=lambda r: min(r[1], end) - max(r[0], start))
            out.append(np.abs(ends_of(section(motion, a, b), "speed") + a - np.array(keyed)))
    return np.array(out), right, len(clips)


def line(label: str, errors: np.ndarray) -> str:
    close = int(np.sum(np.all(errors <= 3, axis=1)))
    return (f"  {label}: mean abs error per stage end {errors.mean():.1f} frames (prep {errors[:, 0].mean():.1f}, "
            f"antic {errors[:, 1].mean():.1f}, exec {errors[:, 2].mean():.1f}, follow {errors[:, 3].mean():.1f}); "
            f"all four within 3 frames: {close}/{len(errors)}")


def builtin_report() -> None:
    from library.manifest import builtin
    from retarget.clips import load_clips

    lib = builtin()
    clips = load_clips(lib)
    print(f"Stage extraction on the {len(clips)} keyed built-in clips (30 fps)")
    for method in METHODS:
        errors = np.array([np.abs(ends_of(clip.motion, method) - np.array(lib.action(name).stages))
                           for name, (clip,) in clips.items()])
        print(line(METHODS[method], errors))


def real_report(mocap: Path = MOCAP) -> None:
    if not mocap.exists():
        print(f"Real clips: {mocap} not found, skipped")
        return
    clips = labels()
    for split in ("tune", "held-out"):
        part = [c for c in clips if c.split == split]
        reps = sum(len(c.reps) for c in part)
        print(f"Stage extraction on the {len(part)} hand-labelled real clips ({reps} repetitions), "
              f"{split}{' (constants chosen here)' if split == 'tune' else ' (not used to choose anything)'}")
        for method in METHODS:
            print(line(METHODS[method], real_errors(part, method, mocap)))
        errors, right, total = split_errors(part, mocap)
        print(line("speed profile, own split into repetitions", errors)
              + f"; repetitions counted right in {right}/{total} clips")


def main() -> None:
    builtin_report()
    real_report()


if __name__ == "__main__":
    main()
