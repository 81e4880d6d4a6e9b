"""``doodle compile``: a doodle into BVH (one file per track), report.json and previews; several
doodles (or folders of them) at once on Dask (:mod:`doodle.app.batch`)."""

from __future__ import annotations

import json
from pathlib import Path

from doodle.core.errors import DoodleError
from doodle.app.cli.options import input_options, library_options, load_input, progress_bar, segmenter_options, segmenter_params


def add_arguments(p) -> None:
    """The arguments of ``doodle compile``."""
    p.add_argument("files", nargs="+", metavar="FILE",
                   help="a doodle file (.doodle, or .csv with --convention); several files, or folders (every "
                        ".doodle and .csv file in them), are compiled in parallel, each into OUTDIR/STEM/")
    p.add_argument("-o", "--output", required=True, metavar="OUTDIR",
                   help="folder of the output (made if missing): TRACK.bvh, report.json and the previews are "
                        "replaced, together, when the compile succeeds; other files in it are left alone")
    input_options(p)
    library_options(p)
    p.add_argument("--fps", type=float, default=30.0, help="output frame rate (default 30)")
    p.add_argument("--scale", type=float, help="doodle-to-world scale (default 8.5: a 20 cm prop, a 1.7 m character)")
    p.add_argument("--threshold", type=float, default=2.0, help="edit-distance threshold of approximate matches")
    p.add_argument("--terrain", metavar="SPEC", help="flat[:H], jacksboro[:SIZE], s1045[:SIZE], "
                   "heightfield:FILE.npz[:SPACING] or mesh:FILE.obj|ply|glb (default flat)")
    p.add_argument("--no-foot-pinning", action="store_true", help="leave feet as the blended clips put them")
    p.add_argument("--jump-arc", choices=["clip", "hermite", "apex"], default="clip",
                   help="jump height from the clip (default), a Hermite arc (alpha 2.5), or one keeping the doodle's apex")
    p.add_argument("--preview", action="store_true", help="also draw plan.png (paths) and keyframes.png (poses)")
    p.add_argument("--time", type=float, default=0.0, help="Laban Time for every segment: sustained -1 … sudden 1")
    p.add_argument("--weight", type=float, default=0.0, help="Laban Weight for every segment: light -1 … strong 1")
    p.add_argument("--edits", metavar="FILE.json", help="per-segment time and weight (see docs/cli.md)")
    p.add_argument("--effort-model", metavar="MODEL.npz",
                   help="Laban Effort model for segments without a given quality (default: the shipped one)")
    p.add_argument("--no-effort", action="store_true", help="do not recognise Time and Weight: neutral unless given")
    p.add_argument("--style", choices=["modifiers", "preferred"], default="modifiers",
                   help="Laban as the thesis's Time/Weight modifiers, or its study's preferred combination "
                        "(gesture retiming + motion scale + reshaping)")
    p.add_argument("--retime", choices=["uniform", "gesture"], default="uniform",
                   help="one-shot clips at an even pace (default) or following the hand's own timing (5.3.3)")
    p.add_argument("--no-cache", action="store_true",
                   help="analyse the library's clips and compile its automata afresh, without reading or writing "
                        "the cache (~/.cache/doodle, $DOODLE_CACHE; DOODLE_NO_CACHE=1 turns it off everywhere)")
    segmenter_options(p)
    g = p.add_argument_group("several files (on Dask)")
    g.add_argument("--workers", type=int, metavar="N",
                   help="local worker processes (default: the number of CPUs, at most one per file)")
    g.add_argument("--scheduler", metavar="ADDRESS",
                   help="a running Dask scheduler (tcp://HOST:8786) whose workers compile instead of local ones")
    p.set_defaults(run=cmd_compile)


def is_batch(names: list[str]) -> bool:
    """Several inputs, or a folder: a batch (:mod:`doodle.app.batch`, imported only then), not
    the single compile."""
    return len(names) != 1 or Path(names[0]).is_dir()


def cmd_compile(args) -> int:
    if is_batch(args.files):
        return cmd_compile_batch(args)
    report, checks = compile_scene(args.files[0], args.output, args, progress_bar("segments"))
    print_compiled(report, checks, args)
    return 0


def check_numbers(args) -> None:
    """The numeric options in their ranges (a DoodleError naming the option if not)."""
    for name, value in (("--time", args.time), ("--weight", args.weight)):
        if not -1.0 <= value <= 1.0:
            raise DoodleError(f"{name} must be between -1 and 1, not {value:g}")
    for name, value in (("--fps", args.fps), ("--scale", args.scale if args.scale is not None else 1.0)):
        if not (value > 0 and value < float("inf")):
            raise DoodleError(f"{name} must be a positive number, not {value:g}")
    if not args.threshold >= 0:
        raise DoodleError(f"--threshold must be 0 or more, not {args.threshold:g}")


def compile_scene(file, output, args, progress=None) -> tuple[dict, dict]:
    """Compile the doodle ``file`` into the folder ``output`` with the options ``args``:
    every file of the output written together at the end (or none). Returns the report
    (as written to report.json) and the animation check of each track."""
    from doodle.core.files import atomic_files, atomic_write, check_dir
    from doodle.app.pipeline import check_edits, compile_doodle, quality
    from doodle.app.report import compiled as compiled_report
    from retarget.bvh import write_bvh
    from retarget.qa import check_scene, check_world

    out = check_dir(output)
    params, mounts = segmenter_params(args)
    terrain = None  # flat
    if args.terrain:
        from retarget.terrain import parse_terrain

        terrain = parse_terrain(args.terrain)
    doodle = load_input(file, args, mounts)
    from doodle.app.pipeline import read_edits

    qualities = read_edits(args.edits) if args.edits else {}
    if args.edits:
        check_edits(args.edits, qualities, {name: None for name in doodle.names})
    check_numbers(args)
    if args.time or args.weight:
        qualities.setdefault((None, None), (args.time, args.weight))
    effort_model = None
    if not args.no_effort:
        from laban.models import load as load_effort_model

        effort_model = load_effort_model(args.effort_model)
    results = compile_doodle(doodle, args.library, not args.no_builtin, params, args.fps, args.scale, args.threshold,
                             not args.no_foot_pinning, terrain, args.jump_arc, args.retime, qualities, args.style,
                             effort_model, progress, cache=not args.no_cache)
    if args.edits:
        check_edits(args.edits, qualities, {r.track: len(r.segments) for r in results})
    paths = {r.track: out / f"{r.track}.bvh" for r in results}
    worlds = {r.track: check_world(r.motion) for r in results}  # shared by the check and the metrics
    checks = check_scene({r.track: r.motion for r in results}, terrain, contacts=results[0].contacts,
                         soles={r.track: r.sole for r in results}, worlds=worlds)
    metrics = {r.track: quality(r, worlds[r.track]) for r in results}
    del worlds
    report = compiled_report(file, args.fps, args.terrain, results, paths, metrics, checks)
    with atomic_files() as staged:  # every file of the output replaced at the end, or none
        for r in results:
            write_bvh(staged(paths[r.track]), r.motion)
        if args.preview:
            from retarget.preview import keyframes, plan_view

            from doodle.app.cli.render import can_preview, preview_sheet

            plan_view(results, {r.track: r.projected for r in results}, staged(out / "plan.png"))
            keyframes(results, staged(out / "keyframes.png"))
            report["preview"] = [str(out / "plan.png"), str(out / "keyframes.png")]
            if can_preview():
                preview_sheet(results, terrain, staged(out / "render.png"), args.fps)
                report["preview"].append(str(out / "render.png"))
        atomic_write(staged(out / "report.json"), [json.dumps(report, indent=2) + "\n"])
    return report, checks


def print_compiled(report: dict, checks: dict, args) -> None:
    """What ``doodle compile FILE`` prints: per track its BVH, check and metrics; the report."""
    out = Path(args.output)
    for name, tr in report["tracks"].items():
        m = tr["metrics"]
        print(f"{tr['bvh']}: {tr['frames']} frames at {args.fps:g} fps; "
              f"{', '.join(s['action'] for s in tr['segments'])}")
        print(f"  check: {checks[name].summary()}")
        print(f"  ground penetration {m['ground_penetration_m']} m, root deviation {m['root_deviation_m']} m, "
              f"transition smoothness {m['transition_smoothness']}")
    print(f"{out / 'report.json'}" + (f"; preview: {', '.join(report['preview'])}" if args.preview else ""))


def compiled_counts(file, output, args) -> tuple[int, int, tuple[str, ...]]:
    """One file of a batch (run on a Dask worker): compiled as :func:`compile_scene` does
    alone, nothing printed; its number of tracks and of frames, and the tracks whose
    animation fails the check."""
    report, _ = compile_scene(file, output, args)
    tracks = report["tracks"]
    return (len(tracks), max((t["frames"] for t in tracks.values()), default=0),
            tuple(name for name, t in tracks.items() if not t.get("check", {}).get("passes", True)))


def check_batch_options(args) -> None:
    """What every file of a batch would fail on alike, checked once before any worker starts:
    the numbers, the calibration, terrain, edits, library and the effort model (read whole:
    a corrupt model fails here, once, not in every file's row)."""
    from doodle.app.cli.options import library_of
    from doodle.app.pipeline import read_edits
    from retarget.terrain import parse_terrain

    check_numbers(args)
    segmenter_params(args)
    if args.terrain:
        parse_terrain(args.terrain)
    if args.edits:
        read_edits(args.edits)
    if not args.no_effort:
        from laban.models import load as load_effort_model

        load_effort_model(args.effort_model)
    library_of(args)


def import_compile_modules() -> None:
    """The modules a compile runs, imported before a local cluster starts: its workers are
    forked from this process (:func:`doodle.app.batch.start_method`) and begin with them, rather
    than each importing them for its first file."""
    import doodle.app.pipeline  # noqa: F401
    import doodle.app.report  # noqa: F401
    import laban.classify  # noqa: F401
    import laban.models  # noqa: F401
    import retarget.bvh  # noqa: F401
    import retarget.qa  # noqa: F401
    import retarget.stylize  # noqa: F401


def cmd_compile_batch(args) -> int:
    from doodle.app import batch
    from doodle.app.cli.options import EXIT_BAD_INPUT
    from doodle.core.files import check_dir

    if args.workers is not None and args.scheduler:
        raise DoodleError("compile: give --workers N or --scheduler ADDRESS, not both")
    if args.workers is not None and args.workers < 1:
        raise DoodleError(f"--workers must be 1 or more, not {args.workers}")
    jobs = batch.plan(batch.expand_inputs(args.files), check_dir(args.output))
    check_batch_options(args)
    if not args.scheduler:
        import_compile_modules()
    options = batch.options_for_workers(args)
    rows = batch.run(jobs, compiled_counts, options, args.workers or batch.default_workers(), args.scheduler,
                     progress_bar("files"))
    batch.show_warnings(rows)
    print("\n".join(batch.table(rows)))
    print(batch.summary(rows, args.output))
    return EXIT_BAD_INPUT if any(r.status != "ok" for r in rows) else 0
