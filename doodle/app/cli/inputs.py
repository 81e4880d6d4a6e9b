"""``doodle tokens``, ``info``, ``import`` and ``calibrate``: what a doodle file holds, CSV
converted, a prop and the Segmenter calibrated."""

from __future__ import annotations

import json

from doodle.core.errors import DoodleError
from doodle.core.files import output_file
from doodle.app.cli.options import each_file, input_options, load_input, segmenter_options, segmenter_params


def add_tokens_arguments(p) -> None:
    """The arguments of ``doodle tokens``."""
    p.add_argument("files", nargs="+", metavar="FILE")
    input_options(p)
    p.add_argument("--json", action="store_true", help="one JSON object per file per line")
    p.add_argument("-v", "--verbose", action="store_true", help="also list each token's time range")
    segmenter_options(p)
    p.set_defaults(run=cmd_tokens)


def add_import_arguments(p) -> None:
    """The arguments of ``doodle import``."""
    p.add_argument("file", metavar="CSV")
    p.add_argument("-o", "--output", required=True, metavar="FILE.doodle")
    p.add_argument("--overwrite", action="store_true", help="replace FILE.doodle if it exists")
    input_options(p)
    p.set_defaults(run=cmd_import)


def add_info_arguments(p) -> None:
    """The arguments of ``doodle info``."""
    p.add_argument("files", nargs="+", metavar="FILE")
    input_options(p)
    p.set_defaults(run=cmd_info)


def add_calibrate_arguments(p) -> None:
    """The arguments of ``doodle calibrate``."""
    p.add_argument("-o", "--output", required=True, metavar="FILE.toml")
    p.add_argument("--overwrite", action="store_true", help="replace FILE.toml if it exists")
    p.add_argument("--forward", metavar="FILE", help="hold the prop still facing forward, then push it forward")
    p.add_argument("--translation", metavar="FILE", help="a minimal translation-only gesture")
    p.add_argument("--rotation", metavar="FILE", help="a minimal rotation-only gesture")
    p.add_argument("--slow", metavar="FILE", help="your slowest deliberate motion")
    input_options(p)
    segmenter_options(p)
    p.set_defaults(run=cmd_calibrate)


def cmd_tokens(args) -> int:
    from doodle.app.report import seconds_of
    from doodle.input.segmenter import tokenize_doodle

    params, mounts = segmenter_params(args)

    def work(path, doodle):
        tokens = tokenize_doodle(doodle, params)
        seconds = seconds_of(doodle)
        if args.json:
            tracks = {name: [{"token": k.name, "start": seconds(k.start), "end": seconds(k.end),
                              "samples": [k.start, k.end]} for k in toks] for name, toks in tokens.items()}
            print(json.dumps({"file": str(path), "tracks": tracks}), flush=True)
            return
        print(f"{path}  ({len(doodle.tracks)} track{'s' * (len(doodle.tracks) != 1)}, "
              f"{doodle.t[-1]:.2f} s at {doodle.rate:g} Hz, device {doodle.device})")
        for name, toks in tokens.items():
            print(f"  {name}: {' '.join(k.name for k in toks) or '(no tokens)'}")
            if args.verbose:
                for k in toks:
                    print(f"    {seconds(k.start):8.3f} {seconds(k.end):8.3f}  {k.name}")

    return each_file(args, mounts, work)


def cmd_import(args) -> int:
    from doodle.input.fileformat import write_doodle

    out = output_file(args.output, args.overwrite)
    doodle = load_input(args.file, args, None, raw=True)
    write_doodle(out, doodle, convention="doodle")
    print(f"{args.output}: {len(doodle.tracks)} track(s), {len(doodle.t)} samples, {doodle.t[-1]:.2f} s")
    return 0


def cmd_info(args) -> int:
    def work(path, doodle):
        print(f"{path}: device {doodle.device}, {doodle.rate:g} Hz nominal, {len(doodle.t)} samples, "
              f"{doodle.t[-1]:.2f} s")
        for tr in doodle.tracks:
            lost = 1.0 - tr.valid.mean()
            extra = "".join(f", {k} {v}" for k, v in (("role", tr.role), ("serial", tr.serial)) if v)
            print(f"  {tr.name}{extra}: lost tracking {lost:.1%} of samples")

    return each_file(args, {}, work)


def cmd_calibrate(args) -> int:
    from doodle.input.calibration import calibrate
    from doodle.input.devices import calibrate_mount
    from doodle.input.settings import write_calibration

    output_file(args.output, args.overwrite)
    params, mounts = segmenter_params(args)
    if args.forward:
        doodle = load_input(args.forward, args, None, raw=True)
        for tr in doodle.tracks:
            mounts[tr.name] = calibrate_mount(tr)
    gestures = [args.translation, args.rotation, args.slow]
    if any(gestures):
        if not all(gestures):
            raise DoodleError("calibrate: --translation, --rotation and --slow go together")
        first = [load_input(g, args, mounts) for g in gestures]
        params = calibrate(*(d.tracks[0] for d in first), first[0].rate, params)
    if not args.forward and not any(gestures):
        raise DoodleError("calibrate: give --forward FILE and/or --translation, --rotation and --slow")
    write_calibration(args.output, params, mounts)
    print(f"{args.output}: eps {params.eps:.4g} m/s, theta {params.theta:.4g} m/rad"
          + "".join(f", mount {n} {tuple(round(x, 4) for x in q)}" for n, q in mounts.items()))
    return 0
