"""The compile pipeline: the one place that ties doodle → grammar → (laban → retarget).

Today it runs the front half: samples → tokens (Segmenter) → action segments (Matcher).
"""

from __future__ import annotations

from doodle.errors import DoodleError
from doodle.model import Doodle
from doodle.segmenter import SegmenterParams, tokenize_doodle
from doodle.tokens import Token
from grammar.library import Compiled, compile_library
from grammar.matcher import Segment, match
from library.manifest import builtin, combine, load_library


def load_actions(library_dir=None, use_builtin: bool = True) -> Compiled:
    """The built-in library, extended or overridden by the one in ``library_dir``."""
    user = load_library(library_dir) if library_dir else None
    if not use_builtin and user is None:
        raise DoodleError("--no-builtin needs --library DIR")
    return compile_library(combine(builtin() if use_builtin else None, user))


def recognize(doodle: Doodle, compiled: Compiled, params: SegmenterParams = SegmenterParams(),
              threshold: float = 2.0, direction_costs: bool = False) -> dict[str, tuple[list[Token], list[Segment]]]:
    """Per track: its tokens and the action segments recognised in them."""
    automaton = compiled.automaton(threshold, direction_costs)
    tokens = tokenize_doodle(doodle, params)
    return {name: (toks, match(toks, automaton, name)) for name, toks in tokens.items()}
