"""Stylising a 10 s clip (target ≤ 20 ms): the built-in Punch repeated to 10 s at 30 fps,
Time then Weight, beside the floor of one forward-kinematics pass over the same clip."""

import numpy as np
from dataclasses import replace

from bench.timing import best_of
from library.manifest import builtin
from retarget.analysis import Stages
from retarget.clips import load_clips
from retarget.skeleton import forward_kinematics
from retarget.stylize import stylize


def main() -> None:
    clip = load_clips(builtin())["Punch"][0]
    m = clip.motion
    reps = int(np.ceil(10.0 / m.duration))
    long = replace(m, translations=np.concatenate([m.translations] * reps), rotations=np.concatenate([m.rotations] * reps))
    st = Stages(clip.stages.preparation, clip.stages.anticipation, clip.stages.execution, clip.stages.follow_through,
                long.frames)
    print(f"Stylisation of a {long.duration:.1f} s clip ({long.frames} frames, {len(long.skeleton)} joints)")
    for lt, lw, label in ((1.0, 0.0, "Time (sudden)"), (0.0, 1.0, "Weight (strong)"), (0.5, -0.5, "Time + Weight")):
        best = best_of(lambda: stylize(long, st, lt, lw))
        print(f"  {label:<16} {best * 1000:7.1f} ms   (target ≤ 20 ms)")
    # a fresh copy each time: forward_kinematics keeps its results per motion, and the floor is a pass, not a look-up
    print(f"  floor, one FK pass {best_of(lambda: forward_kinematics(replace(long))) * 1000:7.1f} ms")


if __name__ == "__main__":
    main()
