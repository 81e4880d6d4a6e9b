"""The Matcher on the built-in 28-action table: sampled strings, synthesised doodles,
approximate matches, unknowns, overlaps, the thesis's main example; library validation."""

import json
import sys
from pathlib import Path

import numpy as np
import pytest

from doodle.app.cli.main import main
from doodle.core.errors import DoodleError
from doodle.core.model import Doodle
from grammar.recognizer import load_actions, recognize
from doodle.input.segmenter import SegmenterParams
from doodle.synth.strokes import perform, synth_track
from doodle.core.tokens import CODES, Token
from grammar.automata import sample
from grammar.library import overlaps
from grammar.matcher import UNKNOWN, Matcher, edit_distance, match

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "examples"))
from make_demo import FIG_4_7, STROKES  # noqa: E402

COMPILED = load_actions()
AUTO = COMPILED.automaton()
NAMES = COMPILED.library.names
ALPHABET = sorted(CODES)


def tokens_of(words):
    return [Token(w, 3 * i, 3 * i + 3) for i, w in enumerate(words)]


def accepting(words):
    return [n for n, d in zip(NAMES, COMPILED.dfas) if d.accepts([CODES[w] for w in words])]


def unique_strings(name, count, seed):
    """Strings of the action's language that no other action accepts."""
    rng = np.random.default_rng(seed)
    dfa, found = COMPILED.dfa(name), []
    for _ in range(400):
        words = sample(dfa, rng)
        if accepting(words) == [name] and words not in found:
            found.append(words)
            if len(found) == count:
                break
    return found


def test_the_table_has_28_actions_with_flags():
    assert len(NAMES) == 28 and len(set(NAMES)) == 28
    walk, jump, punch = (COMPILED.action(n) for n in ("Walk", "Jump", "Punch"))
    assert walk.cyclic and not walk.in_place and not walk.jumping  # Table 4.1
    assert jump.jumping and not jump.cyclic and punch.in_place


def sampled(name, count, seed):
    rng = np.random.default_rng(seed)
    dfa = COMPILED.dfa(name)
    return [sample(dfa, rng) for _ in range(count)]


def expected(words):
    """The action the policy picks among those accepting a string: the most specific."""
    candidates = np.array([NAMES.index(a) for a in accepting(words)])
    return NAMES[AUTO.most_specific(candidates)]


def expected_segments(words):
    """(action, first, stop) the policy gives a string of some action (tokens of equal
    duration, as tokens_of makes them): the most specific acceptor — split after the longest
    leading walk, and before the longest trailing walk longer than what it leaves, when that
    one-shot still accepts the rest."""
    whole = expected(words)
    cyclic = {a.name for a in COMPILED.library.actions if a.cyclic}

    def walk(part):
        walks = [a for a in accepting(part) if a in cyclic]
        return NAMES[AUTO.most_specific(np.array([NAMES.index(a) for a in walks]))] if walks else None

    if whole in cyclic:
        return [(whole, 0, len(words))]
    lo, hi, head, tail = 0, len(words), [], []
    for k in range(len(words) - 1, 0, -1):
        if walk(words[:k]) and whole in accepting(words[k:]):
            head, lo = [(walk(words[:k]), 0, k)], k
            break
    for k in range(lo + 1, hi):
        if walk(words[k:]) and whole in accepting(words[lo:k]) and hi - k > k - lo:
            tail, hi = [(walk(words[k:]), k, len(words))], k
            break
    return head + [(expected(words[lo:hi]) if head or tail else whole, lo, hi)] + tail


@pytest.mark.parametrize("name", NAMES)
def test_sampled_strings_and_their_doodles_are_recognised(name):
    """Strings sampled from each action's language are recognised exactly, as one segment:
    as that action, or — where the string is also another action's (an overlap) — as the
    more specific of them. Every action wins on some of its strings."""
    strings = sampled(name, 12, seed=len(name))
    wins = 0
    for words in strings:
        segs = match(tokens_of(words), AUTO)
        assert [(s.action, s.first, s.stop) for s in segs] == expected_segments(words), words
        assert all(s.exact for s in segs)
        wins += segs[-1].action == name
    assert wins, f"{name} never wins on its own strings: {[expected(w) for w in strings]}"
    mine = [w for w in strings if expected_segments(w) == [(name, 0, len(w))]]
    for k, words in enumerate(mine[:2]):
        doodle = Doodle((perform(words, seed=k),), 90.0)
        toks, segs = recognize(doodle, COMPILED)["c0"]
        assert [t.name for t in toks] == words
        assert [s.action for s in segs] == [name]
        assert segs[0].start == 0 and segs[0].end == len(doodle.t)


def edits(words, rng, n):
    w = list(words)
    for _ in range(n):
        op, i = rng.integers(3), int(rng.integers(len(w) + 1))
        tok = ALPHABET[int(rng.integers(len(ALPHABET)))]
        if op == 0 and i < len(w):
            w[i] = tok
        elif op == 1:
            w.insert(i, tok)
        elif op == 2 and i < len(w) and len(w) > 1:
            del w[i]
    return [x for j, x in enumerate(w) if j == 0 or x != w[j - 1]]


def test_strings_within_distance_two_are_recognised_approximately():
    """Strings one or two edits from an action, where that action is unambiguously the
    nearest (and more than half the tokens match), are that action at that distance, as one
    segment — nearly always: the rest are explained at lower cost by exact actions."""
    rng = np.random.default_rng(1)
    tried, right, actions = 0, 0, set()
    for name in NAMES:
        for words in sampled(name, 20, seed=3 + len(name)):
            for n_edits in (1, 2):
                w = edits(words, rng, n_edits)
                dist = {a: edit_distance(COMPILED.dfa(a), [CODES[x] for x in w]) for a in NAMES}
                d = dist[name]
                if not (1 <= d <= 2 and d < len(w) / 2) or sorted(dist.values())[1] <= d:
                    continue
                tried += 1
                segs = match(tokens_of(w), AUTO)
                if [(s.action, s.exact, s.distance) for s in segs] == [(name, False, d)]:
                    right += 1
                    actions.add(name)
    assert len(actions) >= 18, sorted(set(NAMES) - actions)
    assert right / tried >= 0.95, (right, tried)


def test_strings_far_from_every_action_are_unknown():
    rng = np.random.default_rng(2)
    rotations = [t for t in ALPHABET if t.startswith("R_")]
    for _ in range(30):
        w = list(rng.choice(rotations, size=int(rng.integers(1, 8))))
        w = [x for j, x in enumerate(w) if j == 0 or x != w[j - 1]]
        segs = match(tokens_of(w), AUTO)
        assert [(s.action, s.first, s.stop) for s in segs] == [(UNKNOWN, 0, len(w))]
        assert segs[0].start == 0 and segs[0].end == 3 * len(w)


def test_unknown_between_actions_is_one_segment():
    segs = match(tokens_of(["T_STILL", "R_X", "R_N_Y_Z", "T_STILL", "T_Z", "T_X_Z"]), AUTO)
    assert [(s.action, s.first, s.stop) for s in segs] == [("Idle", 0, 1), (UNKNOWN, 1, 3), ("Idle", 3, 4),
                                                            ("Walk", 4, 6)]


def test_cyclic_walk_absorbs_while_it_matches():
    segs = match(tokens_of(["T_Z", "T_X_Z", "T_Z", "T_N_X_Z", "T_Z", "T_STILL"]), AUTO)
    assert [(s.action, s.stop) for s in segs] == [("Walk", 5), ("Idle", 6)]


def test_overlaps_on_the_default_table_are_resolved_by_specificity():
    found = overlaps(COMPILED)
    assert ("Jump", "Stomp", ("T_Y", "T_N_Y")) in [(o.first, o.second, o.witness) for o in found]
    for o in found:
        segs = match(tokens_of(list(o.witness)), AUTO)
        assert [(s.action, s.first, s.stop) for s in segs] == expected_segments(list(o.witness))
        assert all(s.exact for s in segs)
    assert match(tokens_of(["T_Y", "T_N_Y"]), AUTO)[0].action == "Stomp"


def test_streaming_emits_the_same_segments_as_it_goes():
    words = ["T_STILL", "T_X", "T_STILL", "T_Z", "T_X_Z", "T_STILL", "T_Y", "T_N_Y", "R_X", "T_STILL"]
    m, live = Matcher(AUTO), []
    for t in tokens_of(words):
        live += m.push(t)
    early = len(live)
    live += m.close()
    assert live == match(tokens_of(words), AUTO)
    assert early >= len(live) - 2  # most segments come out before the end of the stream


def test_main_example_fig_4_7():
    """The thesis's main example, synthesised: exactly Fig. 4.7's sequence, and every
    boundary within 3 samples of where the noise-free motion crosses the stillness speed."""
    track, _ = synth_track(STROKES, rate=90.0, seed=7, vary=0.0)
    clean, _ = synth_track(STROKES, rate=90.0, seed=7, vary=0.0, tremor=0, noise=0, drift=0, wobble=0)
    toks, segs = recognize(Doodle((track,), 90.0), COMPILED)["c0"]
    assert [s.action for s in segs] == FIG_4_7
    speed = np.linalg.norm(np.diff(clean.p, axis=0), axis=1) / np.diff(clean.t)
    moving = speed > SegmenterParams().eps
    crossings = np.flatnonzero(moving[1:] != moving[:-1]) + 1
    for seg in segs[1:]:
        t = track.t[seg.start]
        assert np.min(np.abs(clean.t[crossings] - t)) <= 3 / 90.0, (seg.action, t)


def test_demo_file_is_the_main_example(capsys):
    assert main(["recognize", "--json", str(ROOT / "examples" / "demo.doodle")]) == 0
    record = json.loads(capsys.readouterr().out)
    assert [s["action"] for s in record["segments"]] == FIG_4_7
    first = record["segments"][0]
    assert set(first) >= {"track", "action", "start", "end", "exact", "distance"}
    assert first["track"] == "c0" and first["start"] == 0.0 and first["exact"] is True and first["distance"] == 0


# --- libraries ------------------------------------------------------------------------------

def write_library(tmp_path, body, name="mine"):
    folder = tmp_path / name
    folder.mkdir(exist_ok=True)
    (folder / "library.toml").write_text(f'[library]\nname = "{name}"\n\n' + body)
    return folder


@pytest.mark.parametrize("body, message", [
    ('[[actions]]\nname = "Wave"\nexpression = "(T_X | T_N_X"\n', "action 'Wave': column 13"),
    ('[[actions]]\nname = "Wave"\nexpression = "T_X T_WAVE"\n', "unknown token 'T_WAVE'"),
    ('[[actions]]\nname = "Wave"\nexpression = "T_X*"\n', "matches no tokens at all"),
    ('[[actions]]\nname = "Wave"\nexpression = "T_X"\n[[actions]]\nname = "Wave"\nexpression = "T_Y"\n',
     "'Wave' is defined twice"),
    ('[[actions]]\nname = "Wave"\nexpression = "T_X"\ncyclic = "yes"\n', "field 'cyclic' must be true or false"),
    ('[[actions]]\nname = "Wave"\nexpresion = "T_X"\n', "unknown field 'expresion'"),
    ('[[actions]]\nname = "unknown"\nexpression = "T_X"\n', "reserved"),
    ('[[actions]]\nexpression = "T_X"\n', "action #1: field 'name'"),
])
def test_bad_libraries_are_named_errors(tmp_path, body, message):
    folder = write_library(tmp_path, body)
    with pytest.raises(DoodleError, match=message) as err:
        load_actions(folder)
    assert "library.toml" in str(err.value)


def test_user_library_extends_and_overrides(tmp_path, capsys):
    folder = write_library(tmp_path, '[[actions]]\nname = "Spin"\nexpression = "(R_Y)+"\n\n'
                                     '[[actions]]\nname = "Stomp"\nexpression = "T_N_Y T_Y T_N_Y"\n')
    both = load_actions(folder)
    assert len(both.library.names) == 29 and both.library.action("Stomp").expression == "T_N_Y T_Y T_N_Y"
    only = load_actions(folder, use_builtin=False)
    assert only.library.names == ["Spin", "Stomp"]
    spin = tmp_path / "spin.doodle"
    from doodle.input.fileformat import write_doodle

    write_doodle(spin, Doodle((perform(["T_STILL", "R_Y", "T_STILL"], seed=3),), 90.0))
    assert main(["recognize", "--json", "--library", str(folder), "--no-builtin", str(spin)]) == 0
    assert [s["action"] for s in json.loads(capsys.readouterr().out)["segments"]] == [UNKNOWN, "Spin", UNKNOWN]
    assert main(["recognize", "--no-builtin", str(spin)]) == 1
    assert "--no-builtin needs --library" in capsys.readouterr().err


def test_library_check_prints_overlaps(capsys):
    assert main(["library", "check"]) == 0
    out = capsys.readouterr().out
    assert "28 actions" in out and "Jump ~ Stomp: both accept T_Y T_N_Y" in out


def test_library_check_flags_an_action_whose_typical_strings_another_takes(tmp_path, capsys):
    """`Hop`'s typical performances include `T_Y T_N_Y`, which the narrower `Bob` takes; the
    check says so with the string. On the built-in table only Stomp takes a share of Jump's."""
    (tmp_path / "library.toml").write_text(
        '[library]\nname = "t"\n\n[[actions]]\nname = "Hop"\nexpression = "(T_Y)+ (T_Z)* (T_N_Y)+"\n'
        'cyclic = false\nin_place = true\njumping = false\n\n[[actions]]\nname = "Bob"\n'
        'expression = "(T_Y)+ (T_N_Y)+"\ncyclic = false\nin_place = true\njumping = false\n')
    assert main(["library", "check", "--library", str(tmp_path), "--no-builtin"]) == 0
    out = capsys.readouterr().out
    assert "Bob is read for" in out and "of Hop's typical strings, e.g. T_Y T_N_Y" in out
    assert main(["library", "check"]) == 0
    lines = [x for x in capsys.readouterr().out.splitlines() if "typical strings" in x]
    assert lines == [x for x in lines if "Stomp is read for" in x and "of Jump's" in x] and lines
