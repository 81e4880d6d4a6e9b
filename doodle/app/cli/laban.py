"""``doodle laban …``: Laban Effort models — train, evaluate, classify, and label a person's
own recordings for training.

Labelled examples are doodle files whose header says which Drive was performed
(``# x-drive Punch``, optionally ``# x-performer ana``); ``doodle laban label`` writes it.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from doodle.app.cli.options import input_options
from doodle.core.errors import DoodleError
from doodle.core.files import output_dir, output_file

DEFAULT_EVAL_DIR = "out/laban-eval"


def add_arguments(p) -> None:
    """The arguments of ``doodle laban``."""
    lsub = p.add_subparsers(dest="laban_command", required=True, metavar="train|eval|classify|label|record")

    q = lsub.add_parser("train", help="train effort models from labelled doodles and/or generated curves")
    q.add_argument("files", nargs="*", help="labelled doodle files (header x-drive) or folders of them")
    q.add_argument("--synthetic", action="store_true", help="add the generated curves the default model uses")
    q.add_argument("--mocap", metavar="DIR", help="add effort applied to the neutral motion capture clips "
                   "(*_normal_*.bvh) under DIR by the EMOTE-style and stylisation procedures, as the default model")
    q.add_argument("-o", "--output", required=True, metavar="MODEL.npz")
    q.add_argument("--overwrite", action="store_true", help="replace MODEL.npz if it exists")
    q.add_argument("--augment", type=int, default=16, help="sub-sampled copies per training curve (default 16)")
    q.add_argument("--track", default="c0", help="track of each file holding the gesture (default c0)")
    q.add_argument("--sets", default="euclidean,affine,moving",
                   help="HMM feature sets of Table 4.3, comma-separated (default: all three)")
    q.set_defaults(run=cmd_train)

    q = lsub.add_parser("eval", help="accuracy per factor, State and Drive; confusion matrices as PNG")
    q.add_argument("files", nargs="*", help="labelled doodle files or folders (default: generated held-out performers)")
    q.add_argument("--model", metavar="MODEL.npz", help="model to evaluate (default: the shipped one)")
    q.add_argument("-o", "--output", default=DEFAULT_EVAL_DIR, metavar="DIR",
                   help=f"folder for report.json and the confusion PNGs, replaced together (default {DEFAULT_EVAL_DIR})")
    q.add_argument("--track", default="c0")
    q.add_argument("--people", type=int, default=3, help="generated held-out performers (default 3)")
    q.add_argument("--mocap", metavar="DIR",
                   help="neutral motion capture for the cross-procedure tables (default, when no files are given: "
                        "the Bandai clips beside the project, if present)")
    q.add_argument("--held-out", metavar="DIR",
                   help="clips of other people (any *.bvh) for the protocol on movement nothing was chosen on: "
                        "trained on every --mocap clip, tested on these, after the cross-procedure tables (default, "
                        "with the default --mocap: the DeepMimic clips beside the Bandai ones, if present)")
    q.add_argument("--no-cross", action="store_true", help="skip the cross-procedure tables (they take minutes)")
    q.add_argument("--json", action="store_true", help="print the report as JSON")
    q.set_defaults(run=cmd_eval)

    q = lsub.add_parser("classify", help="Time and Weight of each recognised action segment")
    q.add_argument("files", nargs="+", help="doodle files (.doodle, or .csv with --convention)")
    q.add_argument("--model", metavar="MODEL.npz")
    q.add_argument("--whole", action="store_true", help="classify each track as one curve, not per action")
    q.add_argument("--json", action="store_true")
    input_options(q)
    q.set_defaults(run=cmd_classify)

    q = lsub.add_parser("label", help="write the performed Drive into doodle files' headers")
    q.add_argument("files", nargs="+")
    q.add_argument("--drive", required=True, help="Punch, Dab, Press, Glide, Slash, Flick, Wring or Float")
    q.add_argument("--performer", help="who performed it (groups held-out splits)")
    q.set_defaults(run=cmd_label)

    q = lsub.add_parser("record", help="record labelled examples with the controllers (needs SteamVR)")
    q.add_argument("--drive", required=True)
    q.add_argument("-o", "--output", required=True, metavar="FILE.doodle")
    q.add_argument("--overwrite", action="store_true", help="replace FILE.doodle if it exists")
    q.set_defaults(run=cmd_record)


def _drive_name(value: str, where: str) -> str:
    from laban.efforts import DRIVES

    for name in DRIVES:
        if name.lower() == str(value).strip().lower():
            return name
    raise DoodleError(f"{where}: unknown Drive {value!r}; Drives are {', '.join(DRIVES)}")


def _files(items) -> list[Path]:
    out = []
    for item in items:
        path = Path(item)
        if path.is_dir():
            out += sorted(p for p in path.rglob("*.doodle"))
        else:
            out.append(path)
    return out


def labelled(items, track: str = "c0") -> list:
    """Labelled curves from doodle files whose header names the Drive (``x-drive``)."""
    from doodle.input.loader import load
    from laban.train import Labelled

    curves = []
    for path in _files(items):
        if path.suffix.lower() == ".csv":
            raise DoodleError(f"{path}: only doodle files carry a Drive label; convert it with `doodle import` and "
                              "label it with `doodle laban label`")
        doodle = load(path)
        drive = doodle.meta.get("x-drive")
        if drive is None:
            raise DoodleError(f"{path}: no '# x-drive DRIVE' header line — label it with `doodle laban label`")
        if track not in doodle.names:
            raise DoodleError(f"{path}: no track {track!r} (tracks: {', '.join(doodle.names)})")
        tr = doodle.tracks[doodle.names.index(track)]
        performer = doodle.meta.get("x-performer") or path.parent.name
        curves.append(Labelled(tr.t, tr.p, tr.q, _drive_name(drive, str(path)), performer))
    return curves


def cmd_train(args) -> int:
    from doodle.app.cli.options import progress_bar
    from laban.models import save
    from laban.train import DEFAULT_DATA, generated, train

    from laban.features import FEATURE_SETS

    if args.augment < 1:
        raise DoodleError(f"--augment must be 1 or more, not {args.augment}")
    sets = tuple(s.strip() for s in args.sets.split(",") if s.strip())
    if not sets or any(s not in FEATURE_SETS for s in sets):
        raise DoodleError(f"--sets: choose among {', '.join(FEATURE_SETS)}, not {args.sets!r}")
    output_file(args.output, args.overwrite)
    curves = labelled(args.files, args.track) if args.files else []
    held = []
    if args.synthetic:
        curves += generated("train")
        held = generated("calibrate")
    if not curves:
        raise DoodleError("nothing to train on: give labelled doodle files or --synthetic")
    extra = _mocap_items(args.mocap) if args.mocap else []
    info = {"files": [str(f) for f in args.files], "synthetic": DEFAULT_DATA if args.synthetic else None,
            "mocap": {"clips": sorted({e.group for e in extra}), "paths": len(extra),
                      "procedures": sorted({e.source for e in extra})} if extra else None}
    try:
        model = train(curves, held or None, sets=sets, augment=args.augment, progress=progress_bar(), info=info,
                      extra=extra)
    except ValueError as e:
        raise DoodleError(str(e)) from None
    save(model, args.output)
    print(f"{args.output}: {len(curves)} curves, temperature {model.temperature:.3g}, Naive Bayes features "
          + ", ".join(f"{f} {len(b.features)}" for f, b in model.bayes.items()))
    return 0


def _mocap_items(folder) -> list:
    """Effort applied to the neutral clips under ``folder`` by both real-motion procedures."""
    from doodle.app.effort_corpus import emote_items, neutral_clips, stylize_items

    if not Path(folder).is_dir():
        raise DoodleError(f"{folder}: no such folder (--mocap)")
    clips = neutral_clips(folder)
    if not clips:
        raise DoodleError(f"{folder}: no neutral motion capture clips (*/*_normal_*.bvh)")
    print(f"{len(clips)} neutral clips: applying effort (EMOTE-style timing and the stylisation operators)",
          file=sys.stderr)
    return emote_items(clips) + stylize_items(clips)


def cmd_eval(args) -> int:
    from doodle.core.files import atomic_files, atomic_write, check_dir
    from laban.models import load as load_model
    from laban.efforts import DRIVES, STATES
    from laban.report import confusion_png, reliability_png
    from laban.train import evaluate, generated

    out = check_dir(args.output)
    model = load_model(args.model)
    if args.people < 1:
        raise DoodleError(f"--people must be 1 or more, not {args.people}")
    curves = labelled(args.files, args.track) if args.files else generated("test", people=args.people)
    report = evaluate(model, curves)
    report["data"] = [str(f) for f in args.files] or "generated held-out performers (laban.train.DEFAULT_DATA['test'])"
    held_folder = _held_out_folder(args)  # a bad --held-out refused before minutes of work
    cross = _cross(args)
    held = _held_out(args, held_folder) if cross is not None and held_folder else None
    if cross is not None:
        report["cross_procedure"] = cross
        if held is not None:
            report["held_out"] = held
        report["styled_proxy"] = _proxy(args, model)
    pictures = []
    with atomic_files() as staged:  # the pictures and report.json together, or none
        for method, r in report["methods"].items():
            for kind, matrix, labels, title in (("drives", "drive_confusion", DRIVES, "Drives"),
                                                ("states", "state_confusion", STATES, "States (Time + Weight)")):
                pictures.append(str(out / f"{method}_{kind}.png"))
                confusion_png(r[matrix], list(labels), staged(pictures[-1]), f"{method}: {title}")
        for prefix, title, rep in (("cross", "cross-procedure", cross), ("held_out", "held-out clips", held)):
            for group, matrix in (rep or {}).get("state_confusion", {}).items():
                name = group.replace(" → ", "_to_").replace(" + ", "_and_").replace(" ", "_")
                pictures.append(str(out / f"{prefix}_{name}_states.png"))
                confusion_png(matrix, list(STATES), staged(pictures[-1]), f"{title} {group}: States")
        if cross is not None:
            pictures.append(str(out / "reliability.png"))
            reliability_png(cross["reliability"], staged(pictures[-1]),
                            "cross-procedure runs (trained on one procedure, tested on the other)")
        if held is not None:
            pictures.append(str(out / "held_out_reliability.png"))
            reliability_png(held["reliability"], staged(pictures[-1]),
                            "trained as the shipped model (generator and both procedures), tested on the held-out clips")
        report["pictures"] = pictures
        atomic_write(staged(out / "report.json"), [json.dumps(report, indent=2) + "\n"])
    if args.json:
        print(json.dumps(report))
        return 0
    print(f"{len(curves)} curves; accuracy per method (chance: factor 0.5, State 0.25, Drive 0.125)")
    print(f"  {'method':<12} {'space':>6} {'time':>6} {'weight':>6} {'state':>6} {'drive':>6}")
    for method, r in report["methods"].items():
        print(f"  {method:<12} " + " ".join(f"{r[k]:6.3f}" for k in ("space", "time", "weight", "state", "drive")))
    if cross is not None:
        from doodle.app.effort_corpus import held_out_title, table

        print("\n".join(table(cross)))
        rel = cross["reliability"]
        print(f"  calibration (cross-procedure runs): expected calibration error Time {rel['time']['ece']:.3f}, "
              f"Weight {rel['weight']['ece']:.3f}")
        if held is not None:
            print("\n".join(table(held, held_out_title(held))))
            rel = held["reliability"]
            print(f"  calibration (trained as the shipped model, on the held-out clips): expected calibration error "
                  f"Time {rel['time']['ece']:.3f}, Weight {rel['weight']['ece']:.3f}")
        if report["styled_proxy"]["clips"]:
            from doodle.app.effort_corpus import proxy_table

            print("\n".join(proxy_table(report["styled_proxy"])))
    print(f"{out / 'report.json'}; confusion matrices: {', '.join(pictures)}")
    return 0


def _cross(args) -> dict | None:
    """The cross-procedure evaluation, compact for report.json (per-curve probabilities
    folded into State confusion matrices and the reliability table), or None when skipped."""
    from doodle.app.effort_corpus import MOCAP, cross_procedure, reliability

    if args.no_cross or (args.files and not args.mocap):
        return None
    folder = Path(args.mocap) if args.mocap else MOCAP
    if not folder.is_dir():
        if args.mocap:
            raise DoodleError(f"{folder}: no such folder (--mocap)")
        print(f"cross-procedure tables skipped: no motion capture at {folder} (--mocap DIR)", file=sys.stderr)
        return None
    rep = cross_procedure(folder, progress=lambda text: print(text, file=sys.stderr, flush=True))
    rep["reliability"] = reliability(rep)
    return _compact(rep)


def _compact(rep: dict) -> dict:
    """A protocol's report for report.json: the per-curve probabilities folded into State
    confusion matrices."""
    from doodle.app.effort_corpus import state_confusion

    rep["state_confusion"] = state_confusion(rep)
    for run in rep["runs"]:
        for cell in run["cells"].values():
            for key in ("p_sudden", "p_strong", "truth_time", "truth_weight"):
                cell.pop(key)
    return rep


def _held_out_folder(args) -> Path | None:
    """The clips ``--held-out`` names (checked: a folder with clips), else the DeepMimic
    ones beside the default ``--mocap`` if present, else None."""
    from doodle.app.effort_corpus import HELD_OUT, neutral_clips

    if args.held_out:
        folder = Path(args.held_out)
        if not folder.is_dir():
            raise DoodleError(f"{folder}: no such folder (--held-out)")
        if not any(folder.glob("*.bvh")):
            raise DoodleError(f"{folder}: no motion capture clips (*.bvh) (--held-out)")
        if not neutral_clips(folder, "*.bvh"):  # every clip read now: a broken one named before the long part
            raise DoodleError(f"{folder}: no clip moves a hand or the pelvis enough to carry effort (--held-out)")
        return folder
    return None if args.mocap or not HELD_OUT.is_dir() else HELD_OUT


def _held_out(args, folder: Path) -> dict:
    """The protocol on held-out clips (:func:`doodle.app.effort_corpus.held_out`): models
    trained on the generator and one procedure (or both, as the shipped model) applied to
    every ``--mocap`` clip, tested on both applied to the clips in ``folder``; with the
    reliability of the shipped recipe's confidences there."""
    from doodle.app.effort_corpus import MOCAP, held_out, reliability, shipped_groups

    print(f"held-out clips: training on every clip, testing on {folder}", file=sys.stderr, flush=True)
    rep = held_out(Path(args.mocap) if args.mocap else MOCAP, folder)
    rep["reliability"] = reliability(rep, shipped_groups(rep))  # the shipped model's recipe, on clips it never saw
    return _compact(rep)


def _proxy(args, model) -> dict:
    """The styled-clip proxy (:func:`doodle.app.effort_corpus.styled_proxy`) of the model
    evaluated, on the clips beside the neutral ones."""
    from doodle.app.effort_corpus import MOCAP, styled_proxy

    folder = Path(args.mocap) if args.mocap else MOCAP
    return styled_proxy(model.factors, model.threshold, root=folder)


def _unread() -> str:
    """Why a segment's effort was not read (:func:`laban.classify.qualities` left it neutral)."""
    import math

    from laban.classify import MIN_SAMPLES, STILL_REACH, STILL_TURN

    return (f"still (within {STILL_REACH * 100:g} cm and {math.degrees(STILL_TURN):.0f}°) or under {MIN_SAMPLES} "
            "samples")


def cmd_classify(args) -> int:
    from laban.models import load as load_model
    from doodle.app.cli.options import load_input
    from doodle.app.pipeline import samples_of
    from laban.classify import qualities
    from grammar.recognizer import load_actions, recognize
    from doodle.input.repair import repaired
    from doodle.input.segmenter import SegmenterParams

    model = load_model(args.model)
    compiled = None if args.whole else load_actions(None, True)
    failed = 0
    for path in args.files:
        try:
            doodle = repaired(load_input(path, args, None), SegmenterParams().max_gap)  # Effort reads the poses
        except DoodleError as e:
            print(f"doodle: error: {e}", file=sys.stderr)
            failed += 1
            continue
        rows = []
        for tr in doodle.tracks:
            if args.whole:
                spans = [("(whole)", 0, len(tr.t) - 1)]
            else:
                _, segs = recognize(doodle, compiled, SegmenterParams())[tr.name]
                spans = [(s.action, s.start, s.end) for s in segs if s.action != "unknown"]
            efforts = qualities(model, [samples_of(tr, a, b) for _, a, b in spans])  # scored together
            for (action, a, b), e in zip(spans, efforts):
                rows.append({"track": tr.name, "action": action, "start": round(float(tr.t[a]), 3),
                             "end": round(float(tr.t[min(b, len(tr.t) - 1)]), 3), "time": e.time, "weight": e.weight,
                             "p_sudden": round(e.p_sudden, 3), "p_strong": round(e.p_strong, 3),
                             "drive": e.drive, "state": e.state, "read": bool(e.drive)})
        if args.json:
            print(json.dumps({"file": str(path), "segments": rows}))
            continue
        print(path)
        for r in rows:
            where = f"  {r['track']} {r['start']:7.2f} {r['end']:7.2f}  {r['action']:<15}"
            if not r["read"]:
                print(f"{where} neutral, not read: {_unread()}")
                continue
            print(f"{where} time {r['time']:+.2f} (P sudden {r['p_sudden']:.2f})  weight {r['weight']:+.2f} "
                  f"(P strong {r['p_strong']:.2f})  {r['drive']}")
    return 1 if failed else 0


def cmd_label(args) -> int:
    from doodle.input.fileformat import write_doodle
    from doodle.input.loader import load

    drive = _drive_name(args.drive, "--drive")
    for path in args.files:
        if not str(path).endswith(".doodle"):
            raise DoodleError(f"{path}: only doodle files carry labels; convert CSV first with `doodle import`")
        doodle = load(path)
        meta = dict(doodle.meta, **{"x-drive": drive})
        if args.performer:
            meta["x-performer"] = args.performer
        from dataclasses import replace

        write_doodle(path, replace(doodle, meta=meta))
        print(f"{path}: x-drive {drive}" + (f", x-performer {args.performer}" if args.performer else ""))
    return 0


def cmd_record(args) -> int:
    """Record labelled takes with the controllers: each take starts and stops with the
    trigger, then gets the Drive in its header."""
    from dataclasses import replace

    from doodle.input.fileformat import write_doodle
    from doodle.input.loader import load
    from doodle.app.recorder import record
    from doodle.input.sources import OpenVRSource

    drive = _drive_name(args.drive, "--drive")
    out = output_file(args.output, args.overwrite)
    try:
        source = OpenVRSource()
    except DoodleError as e:
        raise DoodleError(f"{e}; or record elsewhere and label the file with `doodle laban label FILE "
                          f"--drive {drive}`") from None
    try:
        output_dir(out.parent if str(out.parent) else ".")
        print(f"press the trigger, perform a {drive}, press the trigger again", flush=True)
        result = record(source, args.output, wait_for_trigger=True, overwrite=args.overwrite)
    finally:
        source.close()
    doodle = load(result.path)
    write_doodle(result.path, replace(doodle, meta=dict(doodle.meta, **{"x-drive": drive})))
    print(f"{result.path}: {result.duration:.2f} s, x-drive {drive}")
    return 0
