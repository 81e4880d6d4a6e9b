"""``doodle stylize``: Laban Time and Weight applied to a BVH clip."""

from __future__ import annotations

from doodle.core.errors import DoodleError


def add_arguments(p) -> None:
    """The arguments of ``doodle stylize``."""
    p.add_argument("clip", metavar="CLIP.bvh")
    p.add_argument("--time", type=float, default=0.0, help="L_t in [-1, 1]: sustained < 0 < sudden")
    p.add_argument("--weight", type=float, default=0.0, help="L_w in [-1, 1]: light < 0 < strong")
    p.add_argument("--stages", metavar="P,A,E,F", help="frames ending preparation, anticipation, execution, "
                   "follow-through (default: extracted)")
    p.add_argument("-o", "--output", required=True, metavar="OUT.bvh")
    p.add_argument("--overwrite", action="store_true", help="replace OUT.bvh (and the --compare PNG) if they exist")
    p.add_argument("--compare", metavar="PNG", help="neutral and stylised side by side, with end-effector paths and "
                   "the signature measures (peak speed, execution, extent, impact) of the most moving hand or foot")
    p.add_argument("--cyclic", action="store_true",
                   help="a cycle (a walk): Weight as upper-body swing and posture only, no retiming; Time ignored")
    p.set_defaults(run=cmd_stylize)


def cmd_stylize(args) -> int:
    from doodle.core.files import atomic_files, output_file
    from retarget.analysis import Stages, stages
    from retarget.bvh import read_bvh_with_unit, write_bvh
    from retarget.stylize import stylize

    for name, value in (("--time", args.time), ("--weight", args.weight)):
        if not -1.0 <= value <= 1.0:
            raise DoodleError(f"{name} must be between -1 and 1, not {value:g}")
    output = output_file(args.output, args.overwrite)
    compare = output_file(args.compare, args.overwrite) if args.compare else None
    if compare is not None and compare.resolve() == output.resolve():
        raise DoodleError(f"{compare}: --compare names the output clip; give the picture a name of its own")
    motion, unit = read_bvh_with_unit(args.clip)
    if args.stages:
        try:
            ends = [int(x) for x in args.stages.split(",")]
        except ValueError:
            raise DoodleError(f"--stages: expected four frame numbers like 8,16,24,32, not {args.stages!r}") from None
        if len(ends) != 4 or ends != sorted(ends) or ends[-1] > motion.frames:
            raise DoodleError(f"--stages: four increasing frame numbers within the clip's {motion.frames} frames")
        found = Stages(*ends, motion.frames)
    else:
        found = stages(motion)
    if args.cyclic:
        from retarget.stylize import cyclic

        out = cyclic(motion, args.weight)
    else:
        out = stylize(motion, found, args.time, args.weight)
    lines = []
    with atomic_files() as staged:  # the clip and its picture together, or neither
        write_bvh(staged(output), out, unit=unit)
        if compare is not None:
            lines = _compare(motion, out, staged(compare), args)
    print(f"{output}: {out.frames} frames at {out.fps:.4g} fps ({out.duration:.2f} s; neutral "
          f"{motion.duration:.2f} s), time {args.time:+g}, weight {args.weight:+g}; stages "
          f"{found.preparation},{found.anticipation},{found.execution},{found.follow_through}")
    if compare is not None:
        print(compare)
        print("  " + "; ".join(lines))
    return 0


def _compare(motion, out, path, args) -> list[str]:
    """Draw the --compare picture to ``path``; the signature measures written on it."""
    from retarget.analysis import guess_roles
    from retarget.effort_signature import signature
    from retarget.preview import compare_picture

    roles = guess_roles(motion.skeleton)
    before = signature(motion)
    after = signature(out, before.effector)
    effectors = [before.effector] + [roles[k] for k in ("right_hand", "left_hand", "right_foot", "left_foot")
                                     if k in roles and roles[k] != before.effector]
    lines = [f"{label}: {getattr(before, k):.2f} → {getattr(after, k):.2f} {unit} (×{getattr(after, k) / max(getattr(before, k), 1e-9):.2f})"
             for label, k, unit in (("peak speed", "peak_speed", "m/s"), ("execution", "execution", "s"),
                                    ("extent", "extent", "m"), ("impact", "sharpness", "m/s²"))]
    compare_picture(motion, out, effectors, path, f"time {args.time:+g}, weight {args.weight:+g}",
                    notes=[f"{motion.skeleton.names[before.effector]}, neutral → styled"] + lines)
    return lines
