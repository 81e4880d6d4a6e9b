"""``doodle qa OUTDIR|FILE.bvh``: the animation check (:mod:`retarget.qa`) of a compiled scene —
feet sliding, pops, one-frame turns, hovering and sinking, characters interpenetrating,
interaction contacts missed and reactions leading their cause (from report.json's
``interactions``) — each with the frames it happens in."""

from __future__ import annotations

import json
from pathlib import Path

from doodle.core.errors import DoodleError
from doodle.core.files import within

EXIT_FAILS = 4  # the animation fails the check (bad input is 1)


def add_arguments(p) -> None:
    """The arguments of ``doodle qa``."""
    p.add_argument("folder", metavar="OUTDIR",
                   help="what `doodle compile -o OUTDIR` wrote, or a folder of BVH files, or one BVH file (each on "
                        "its own floor)")
    p.add_argument("--terrain", metavar="SPEC", help="the ground (default: the one report.json names, else flat)")
    p.add_argument("-v", "--verbose", action="store_true", help="list the frames of every finding")
    p.set_defaults(run=cmd_qa)


def cmd_qa(args) -> int:
    from retarget.bvh import read_bvh
    from retarget.qa import check_scene
    from retarget.terrain import parse_terrain

    folder = Path(args.folder)
    one = folder.is_file() and folder.suffix.lower() == ".bvh"
    if one:
        folder = folder.parent
    elif not folder.is_dir():
        raise DoodleError(f"{folder}: not a folder or a BVH file (give what `doodle compile -o` wrote)")
    report_path = folder / "report.json"
    spec, ground, contacts, soles = args.terrain, 0.0, (), {}
    if one:  # a clip on its own: its floor where its feet rest
        paths, ground = [Path(args.folder)], None
    elif report_path.exists():
        try:
            report = json.loads(report_path.read_text(encoding="utf-8"))
            # the BVH files beside it, as compile writes them: a report someone sends names no other file
            paths = [within(folder, Path(t["bvh"]).name, f"{report_path}: track {name!r}")
                     for name, t in report["tracks"].items()]
            spec = spec or (report.get("terrain") if report.get("terrain") != "flat" else None)
            interactions = report.get("interactions", [])
            soles = {Path(t["bvh"]).stem: float(t.get("sole_m", 0.0)) for t in report["tracks"].values()}
        except (OSError, ValueError, KeyError, TypeError, AttributeError) as e:
            raise DoodleError(f"{report_path}: not a report of `doodle compile` ({e})") from None
        from doodle.app.report import read_contacts

        contacts = read_contacts({"interactions": interactions}, str(report_path))
    else:  # not compiled here: each clip's floor is where its feet rest
        paths, ground = sorted(folder.glob("*.bvh")), None
    if not paths:
        raise DoodleError(f"{folder}: no BVH files to check")
    motions = {p.stem: read_bvh(p) for p in paths}
    checks = check_scene(motions, parse_terrain(spec) if spec else None, ground=ground, contacts=contacts, soles=soles)
    for name, c in checks.items():
        print(f"{folder / (name + '.bvh')}: {c.frames} frames at {c.fps:g} fps")
        print(f"  {c.summary()}")
        if args.verbose:
            for what, frames in (("sliding", c.sliding), ("pops", c.pops), ("one-frame turns", c.turns),
                                 ("hovering", c.hovering), ("sinking", c.sinking), ("contacts missed", c.missed),
                                 ("reaction leading its cause", c.leads),
                                 *((f"interpenetrating {k}", v) for k, v in c.touching.items())):
                if frames:
                    print(f"    {what}: frames {_ranges(frames)}")
    return 0 if all(c.passes for c in checks.values()) else EXIT_FAILS


def _ranges(frames) -> str:
    """1 2 3 7 9 10 → '1–3, 7, 9–10'."""
    out, start, last = [], None, None
    for f in list(frames) + [None]:
        if f is not None and last is not None and f == last + 1:
            last = f
            continue
        if start is not None:
            out.append(f"{start}" if start == last else f"{start}–{last}")
        start = last = f
    return ", ".join(out)
