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

from doodle.core.errors import DoodleError
from doodle.app.cli.options import EXIT_BAD_INPUT, error

EXIT_USAGE = 2


def build_parser() -> argparse.ArgumentParser:
    from doodle.app.cli import compile, inputs, laban, learn, library, qa, recognize, record, render, replay, stylize

    parser = argparse.ArgumentParser(prog="doodle", description="Spatial motion doodles: VR controller motion to character animation.")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    inputs.add_tokens_parser(sub)
    for command in (recognize, compile, qa, stylize, library, record, render, laban, learn, replay, inputs):
        command.add_parser(sub)
    return parser


def _warning(message, category, filename, lineno, file=None, line=None) -> None:
    print(f"doodle: warning: {message}", file=sys.stderr, flush=True)


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
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
