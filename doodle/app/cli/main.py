"""The ``doodle`` command line: one module per command family, options shared
(:mod:`doodle.app.cli.options`).

Every command reports bad input as one line ``doodle: error: …`` naming the file (and line,
track or field) and exits non-zero; set ``DOODLE_DEBUG=1`` to see a traceback instead.
"""

from __future__ import annotations

import argparse
import os
import sys
import warnings
from importlib import import_module

from doodle.core.errors import DoodleError
from doodle.app.cli.options import EXIT_BAD_INPUT, error

EXIT_USAGE = 2

# Every command in the order ``doodle --help`` lists them: its name, its line of help there,
# and the module of doodle.app.cli and function that give its parser its arguments.
COMMANDS = (
    ("tokens", "print the motion tokens of doodle or CSV files", "inputs", "add_tokens_arguments"),
    ("recognize", "recognise actions in doodle or CSV files", "recognize", "add_arguments"),
    ("compile", "compile a doodle into BVH animation (one file per track) and report.json; "
                "several doodles, or folders of them, at once", "compile", "add_arguments"),
    ("qa", "check a compiled scene's animation: sliding, pops, turns, hovering, interpenetration", "qa",
     "add_arguments"),
    ("stylize", "apply Laban Time and Weight to a BVH clip", "stylize", "add_arguments"),
    ("library", "action libraries: list, show, check, sheet, import", "library", "add_arguments"),
    ("record", "record a doodle from the controllers (SteamVR), showing actions live", "record", "add_arguments"),
    ("render", "render the compiled animation in 3D: key-frame sheet (.png), .gif or .mp4", "render",
     "add_arguments"),
    ("laban", "Laban Effort models: train, eval, classify, label, record", "laban", "add_arguments"),
    ("learn", "learn a new action from three (or more) performed examples", "learn", "add_arguments"),
    ("replay", "stream a recorded doodle through the live recogniser, printing actions", "replay", "add_arguments"),
    ("import", "convert a CSV recording into a doodle file", "inputs", "add_import_arguments"),
    ("info", "describe doodle files: device, rate, tracks, lost tracking", "inputs", "add_info_arguments"),
    ("calibrate", "measure a prop's forward and the Segmenter's thresholds", "inputs", "add_calibrate_arguments"),
)


def build_parser(commands=None) -> argparse.ArgumentParser:
    """The command line's parser with the arguments of the ``commands`` named (default: every
    command); the others are there by name and help line only, their modules not imported."""
    parser = argparse.ArgumentParser(prog="doodle", description="Spatial motion doodles: VR controller motion to character animation.")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name, text, module, function in COMMANDS:
        p = sub.add_parser(name, help=text)
        if commands is None or name in commands:
            getattr(import_module(f"doodle.app.cli.{module}"), function)(p)
    return parser


def named_command(argv: list[str]) -> list[str]:
    """The command ``argv`` runs (its first word not an option), if it is one: all of the
    parser that parsing it needs. The rest of ``argv`` is left to argparse."""
    first = next((word for word in argv if not word.startswith("-")), None)
    return [first] if any(first == name for name, *_ in COMMANDS) else []


def _warning(message, category, filename, lineno, file=None, line=None) -> None:
    print(f"doodle: warning: {message}", file=sys.stderr, flush=True)


BLAS_THREADS = "1"  # unless the environment says otherwise (OPENBLAS_NUM_THREADS, read when numpy is imported)


def main(argv: list[str] | None = None) -> int:
    # doodle's matrices are small: OpenBLAS's own thread per core only spins (a 60 s doodle's
    # compile spent 0.72 s of CPU instead of 0.44 s for the same wall time, and took cores
    # from whatever else runs — a live view, a batch's other worker)
    os.environ.setdefault("OPENBLAS_NUM_THREADS", BLAS_THREADS)
    argv = sys.argv[1:] if argv is None else argv
    args = build_parser(named_command(argv)).parse_args(argv)
    warnings.showwarning = _warning
    try:
        if getattr(args, "no_builtin", False) and not getattr(args, "library", None):
            raise DoodleError("--no-builtin needs --library DIR")
        return args.run(args)
    except DoodleError as e:
        error(e)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        print("doodle: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        return 0
    except Exception as e:  # a bug, not bad input: one line unless debugging
        if os.environ.get("DOODLE_DEBUG"):
            raise
        print(f"doodle: internal error: {type(e).__name__}: {e} (set DOODLE_DEBUG=1 for a traceback)", file=sys.stderr)
        return 3


if __name__ == "__main__":
    sys.exit(main())
