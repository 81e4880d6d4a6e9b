"""The motion-token language: expressions, compacted-language automata, overlap witnesses,
edit distance to a language."""

import itertools
import re

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from doodle.core.errors import DoodleError
from doodle.core.tokens import CODES
from grammar.automata import check_language, compile_expression, intersection_witness, sample, shortest
from grammar.expr import Alt, Cat, Repeat, Sym, parse, to_text
from grammar.matcher import Automaton, edit_distance, substitution_costs

SMALL = ["T_Z", "T_Y", "T_N_Y"]  # a small alphabet, so random languages overlap


def codes(text: str) -> list[int]:
    return [CODES[t] for t in text.split()]


# --- expressions --------------------------------------------------------------------------

def exprs(depth=3):
    leaf = st.sampled_from(SMALL).map(lambda n: Sym(CODES[n]))
    return st.recursive(
        leaf,
        lambda inner: st.one_of(
            st.lists(inner, min_size=2, max_size=3).map(lambda xs: Cat(tuple(xs))),
            st.lists(inner, min_size=2, max_size=3).map(lambda xs: Alt(tuple(xs))),
            st.tuples(inner, st.sampled_from([(0, True), (1, True), (0, False)])).map(
                lambda t: Repeat(t[0], *t[1])),
        ),
        max_leaves=6,
    )


@settings(max_examples=60, deadline=None)
@given(exprs())
def test_expression_text_round_trips(node):
    text = to_text(node)
    assert to_text(parse(text)) == text


@pytest.mark.parametrize("text, column, what", [
    ("(T_Z | T_Y", 11, "a ')' is missing"), ("T_Z |", 6, "ends too early"), ("T_Q+", 1, "unknown token 'T_Q'"),
    ("T_Z (T_N_K)*", 6, "unknown token"), ("* T_Z", 1, "unexpected '*'"), ("T_Z))", 4, "unexpected ')'"),
    ("T_Z, T_Y", 4, "unexpected ','"),
])
def test_malformed_expressions_name_action_and_column(text, column, what):
    with pytest.raises(DoodleError) as err:
        parse(text, "Wave")
    assert f"action 'Wave': column {column}" in str(err.value) and what in str(err.value)


def test_empty_expression_and_empty_token_string():
    with pytest.raises(DoodleError, match="empty expression"):
        parse("  ", "Wave")
    with pytest.raises(DoodleError, match="matches no tokens at all"):
        check_language(compile_expression(parse("T_Z* T_Y?")), "Wave")


# --- the compacted language ---------------------------------------------------------------

def reference_accepts(text: str, word: list[str]) -> bool:
    """Is the compacted ``word`` itself a string of the expression (checked with ``re``)?
    Neighbouring groups do not share a run: ``(T_Y)+ (T_N_Y | T_Y)+`` needs a ``T_N_Y``."""
    letter = {name: chr(0x100 + CODES[name]) for name in CODES}
    pattern = re.compile(re.sub(r"[A-Z][A-Z_]*", lambda m: letter[m.group()], text).replace(" ", ""))
    return pattern.fullmatch("".join(letter[w] for w in word)) is not None


@settings(max_examples=60, deadline=None)
@given(exprs(), st.lists(st.sampled_from(SMALL), max_size=4))
def test_dfa_accepts_exactly_the_compacted_language(node, word):
    word = [w for i, w in enumerate(word) if i == 0 or w != word[i - 1]]  # compacted input
    dfa = compile_expression(node)
    assert dfa.accepts([CODES[w] for w in word]) == reference_accepts(to_text(node), word)


def test_groups_do_not_share_a_run():
    """§4.2.3: the thesis removes the + and enumerates one token per group, so each group an
    expression requires reads its own run of the compacted stream: `(T_Y)+ (T_N_Y | T_Y)+`
    does not read a lone `T_Y` (Pick up's groups swallowed a Jump's apex that way), `T_Z T_Z`
    reads nothing, while a group's own + still repeats its body."""
    assert not compile_expression(parse("(T_Y)+ (T_N_Y | T_Y)+")).accepts(codes("T_Y"))
    assert compile_expression(parse("(T_Y)+ (T_N_Y | T_Y)+")).accepts(codes("T_Y T_N_Y T_Y"))
    assert not compile_expression(parse("T_Z T_Z")).accept.any()
    assert compile_expression(parse("T_Z+")).accepts(codes("T_Z"))
    walk = compile_expression(parse("(T_Z | T_X_Z | T_N_X_Z)+"))
    assert walk.accepts(codes("T_Z T_X_Z T_Z T_N_X_Z")) and not walk.accepts(codes("T_Z T_Y"))
    assert walk.size == 4  # start + one state per last token: minimal


@settings(max_examples=40, deadline=None)
@given(exprs(), exprs())
def test_overlap_witness_is_shortest_common_string(a, b):
    da, db = compile_expression(a), compile_expression(b)
    witness = intersection_witness(da, db)
    words = [list(w) for n in range(1, 6) for w in itertools.product(SMALL, repeat=n)
             if all(x != y for x, y in zip(w, w[1:]))]
    common = [w for w in words if da.accepts([CODES[x] for x in w]) and db.accepts([CODES[x] for x in w])]
    if witness is None:
        assert not common
    else:
        assert da.accepts([CODES[x] for x in witness]) and db.accepts([CODES[x] for x in witness])
        if common:
            assert len(witness) == min(len(w) for w in common)


def test_thesis_overlap_example():
    """§4.2.4: R1 = T_Z* T_Y+ T_X* and R2 = T_Z* T_Y+ intersect on T_Z T_Y (or T_Y)."""
    w = intersection_witness(compile_expression(parse("T_Z* T_Y+ T_X*")), compile_expression(parse("T_Z* T_Y+")))
    assert w == ["T_Y"]


def test_samples_and_shortest_are_in_the_language():
    dfa = compile_expression(parse("((T_Z)* (T_N_Z)*) (T_Y)+ (T_N_Y | T_Y_Z)+ (T_N_Y)*"))
    rng = np.random.default_rng(0)
    for _ in range(50):
        assert dfa.accepts([CODES[t] for t in sample(dfa, rng)])
    assert shortest(dfa) == ["T_Y", "T_N_Y"] or len(shortest(dfa)) == 2


# --- edit distance to a language ----------------------------------------------------------

@settings(max_examples=60, deadline=None)
@given(exprs(), st.lists(st.sampled_from(SMALL + ["T_X", "R_Y"]), min_size=1, max_size=6), st.booleans())
def test_vectorised_distance_equals_plain_dynamic_programme(node, word, directional):
    """The Matcher's stacked-automaton DP gives the same distance as a plain DP over one DFA
    (capped at threshold + 1)."""
    dfa = compile_expression(node)
    assume(dfa.accept.any())  # an empty language is refused when a library loads
    auto = Automaton(["A"], [dfa], threshold=2.0, direction_costs=directional)
    d = auto.initial
    for w in word:
        d = auto.step(d, CODES[w])
    expected = edit_distance(dfa, [CODES[w] for w in word], substitution_costs(directional))
    assert auto.accept_costs(d)[0] == pytest.approx(min(expected, 3.0))


def test_direction_costs_are_cheaper_for_near_directions():
    c = substitution_costs(True)
    assert c[CODES["T_Z"], CODES["T_Z"]] == 0
    assert c[CODES["T_Z"], CODES["T_Y_Z"]] == pytest.approx(0.625)
    assert c[CODES["T_Z"], CODES["T_N_Z"]] == pytest.approx(1.0)
    assert c[CODES["T_Z"], CODES["R_Z"]] == 1.0 and c[CODES["T_STILL"], CODES["T_Z"]] == 1.0
    assert substitution_costs(False)[CODES["T_Z"], CODES["T_Y_Z"]] == 1.0
