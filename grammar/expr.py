"""Action expressions: regular expressions over motion tokens, parsed with lark.

Syntax: token names (``T_Z``, ``R_N_X_Y``, ``T_STILL`` — see :mod:`doodle.core.tokens`),
concatenation by juxtaposition, ``|`` alternation, postfix ``*`` ``+`` ``?`` and
parentheses::

    ((T_Z)* (T_N_Z)*) (T_Y)+ (T_N_Y | T_Y_Z)+ (T_N_Y)*

A malformed expression or an unknown token is a DoodleError naming the action and the
column (1-based) where the problem is.
"""

from __future__ import annotations

from dataclasses import dataclass

from doodle.core.errors import DoodleError
from doodle.core.tokens import CODES, NAMES


@dataclass(frozen=True)
class Sym:
    code: int  # a token code of doodle.core.tokens


@dataclass(frozen=True)
class Cat:
    parts: tuple


@dataclass(frozen=True)
class Alt:
    options: tuple


@dataclass(frozen=True)
class Repeat:
    node: object
    least: int  # 0 for * and ?, 1 for +
    many: bool  # True for * and +, False for ?


_GRAMMAR = r"""
?start: alt
?alt: cat ("|" cat)*
?cat: rep+
?rep: atom POSTFIX*
?atom: NAME | "(" alt ")"
POSTFIX: "*" | "+" | "?"
NAME: /[A-Za-z][A-Za-z0-9_]*/
%import common.WS
%ignore WS
"""


_LARK: dict = {}  # the parser and the tree builder, made on the first parse: a compile whose
# automata come from the cache (doodle.app.libcache) never imports lark nor builds its tables


def _lark() -> dict:
    if not _LARK:
        from lark import Lark, Token, Transformer

        class Build(Transformer):
            def __init__(self, action: str):
                super().__init__()
                self.action = action

            def NAME(self, tok: Token):
                code = CODES.get(str(tok))
                if code is None:
                    raise DoodleError(f"action {self.action!r}: column {tok.column}: unknown token {str(tok)!r}")
                return Sym(code)

            def alt(self, children):
                return Alt(tuple(o for c in children for o in (c.options if isinstance(c, Alt) else (c,))))

            def cat(self, children):
                return Cat(tuple(p for c in children for p in (c.parts if isinstance(c, Cat) else (c,))))

            def rep(self, children):
                node = children[0]
                for op in children[1:]:
                    node = Repeat(node, 1 if op == "+" else 0, op != "?")
                return node

        _LARK.update(parser=Lark(_GRAMMAR, parser="lalr", maybe_placeholders=False), build=Build)
    return _LARK


def parse(text: str, action: str = "?") -> object:
    """The expression tree of ``text``; DoodleError naming ``action`` and the column."""
    if not text.strip():
        raise DoodleError(f"action {action!r}: empty expression")
    from lark import Token, UnexpectedEOF, UnexpectedInput

    try:
        tree = _lark()["parser"].parse(text)
    except UnexpectedInput as e:
        at_end = isinstance(e, UnexpectedEOF) or getattr(getattr(e, "token", None), "type", "") == "$END"
        if at_end:
            hint = " (a ')' is missing)" if text.count("(") > text.count(")") else ""
            raise DoodleError(f"action {action!r}: column {len(text.rstrip()) + 1}: expression ends too early{hint}: {text!r}") from None
        found = text[e.pos_in_stream] if e.pos_in_stream is not None and e.pos_in_stream < len(text) else "?"
        raise DoodleError(f"action {action!r}: column {e.column}: unexpected {found!r} in {text!r}") from None
    try:
        build = _lark()["build"](action)
        return build.transform(tree) if not isinstance(tree, Token) else build.NAME(tree)
    except DoodleError:
        raise
    except Exception as e:  # lark wraps errors raised inside the transformer
        inner = getattr(e, "orig_exc", None)
        if isinstance(inner, DoodleError):
            raise inner from None
        raise


def to_text(node) -> str:
    """Canonical text of an expression tree (round-trips through :func:`parse`)."""
    if isinstance(node, Sym):
        return NAMES[node.code]
    if isinstance(node, Cat):
        return " ".join(to_text(p) if not isinstance(p, Alt) else f"({to_text(p)})" for p in node.parts)
    if isinstance(node, Alt):
        return " | ".join(to_text(o) for o in node.options)
    op = "+" if node.least == 1 else ("*" if node.many else "?")
    inner = to_text(node.node)
    return f"{inner}{op}" if isinstance(node.node, Sym) else f"({inner}){op}"
