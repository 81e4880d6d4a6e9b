"""Options and helpers every command shares: input files, the Segmenter's settings, the
library, per-file error reporting, progress bars."""

from __future__ import annotations

import argparse
import sys

from doodle.core.errors import DoodleError

EXIT_BAD_INPUT = 1



def segmenter_options(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group("segmenter")
    g.add_argument("--calibration", metavar="FILE", help="TOML from `doodle calibrate` (thresholds, mounts)")
    g.add_argument("--eps", type=float, help="stillness threshold, m/s (default 0.05)")
    g.add_argument("--theta", type=float, help="translation if |v| >= theta*|w|, m/rad (default 0.3)")
    g.add_argument("--smoothing", choices=["laplacian", "savgol"], help="denoising filter (default laplacian)")
    g.add_argument("--max-gap", type=float, help="seconds of lost tracking repaired by interpolation (default 0.5)")


def input_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("--convention", choices=["unity", "openvr", "doodle"], help="coordinate convention of CSV input")
    p.add_argument("--columns", metavar="MAP", help="CSV column map, e.g. t=time,c0.px=x,c0.py=y,…")
    p.add_argument("--tracks", metavar="NAMES", help="comma-separated track names (default: all)")


def library_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("--library", metavar="DIR", help="a user library (folder with library.toml)")
    p.add_argument("--no-builtin", action="store_true", help="use only the library given with --library")


def segmenter_params(args):
    from dataclasses import replace

    from doodle.input.segmenter import SegmenterParams
    from doodle.input.settings import read_calibration

    params, mounts = SegmenterParams(), {}
    if args.calibration:
        params, mounts = read_calibration(args.calibration, params)
    given = {k: getattr(args, a) for k, a in (("eps", "eps"), ("theta", "theta"), ("smoothing", "smoothing"),
                                             ("max_gap", "max_gap")) if getattr(args, a) is not None}
    return replace(params, **given), mounts


def load_input(path, args, mounts, raw=False):
    from doodle.input.loader import load

    from pathlib import Path

    is_csv = Path(path).suffix.lower() == ".csv"
    if is_csv and args.convention is None and Path(path).is_file():
        raise DoodleError(f"{path}: a CSV file does not say its coordinate convention; pass --convention unity, "
                          "openvr or doodle")
    if not is_csv and args.convention is not None and Path(path).is_file():
        raise DoodleError(f"{path}: --convention applies to CSV input; a doodle file's header names its own")
    columns = None
    if args.columns:
        from doodle.input.csvimport import parse_column_map

        columns = parse_column_map(args.columns)
    tracks = [t.strip() for t in args.tracks.split(",") if t.strip()] if args.tracks else None
    return load(path, args.convention, columns, tracks, mounts, raw)


def each_file(args, mounts, work) -> int:
    """``work(path, doodle)`` for every input file; a bad file is reported in one line and
    the others still run; non-zero exit status if any failed."""
    failed = 0
    for path in args.files:
        try:
            work(path, load_input(path, args, mounts))
        except DoodleError as e:
            error(e)
            failed += 1
    return EXIT_BAD_INPUT if failed else 0


def show_progress(stage: str, i: int, n: int) -> None:
    """Draw (or redraw) the progress bar of ``stage`` on stderr: ``i`` of ``n`` done."""
    done = int(24 * i / max(n, 1))
    print(f"\r  {stage:<14} [{'#' * done}{'.' * (24 - done)}] {i}/{n}", end="" if i < n else "\n",
          file=sys.stderr, flush=True)


def progress_bar(stage: str | None = None):
    """A progress callback for long work when stderr is a terminal, else None: ``(i, n)``
    for one ``stage``, or ``(stage, i, n)`` without one."""
    if not sys.stderr.isatty():
        return None
    return show_progress if stage is None else (lambda i, n: show_progress(stage, i, n))


def error(e: BaseException) -> None:
    print(f"doodle: error: {e}", file=sys.stderr, flush=True)


def library_of(args):
    """The library the options name: the built-in one (unless ``--no-builtin``) combined
    with the one in ``--library``."""
    from library.manifest import load_combined

    return load_combined(args.library, not args.no_builtin)[0]
