"""Matcher speed with the 28 built-in actions, and the overlap check of the whole table.

* Streaming Matcher: cost per token over one hour of tokens (action strings sampled from
  the table, separated by pauses, one token in ten edited), beside a naive baseline in the
  same run: Python's ``re`` re-run over the whole current prefix, for every action, at
  every token (exact matching only — it does less than the Matcher). Costs are the CPU
  time of the thread (wall-clock time too, which on a shared machine adds other jobs'
  time slices), the median of three runs with fresh tables (the Matcher interns the rows
  it meets: :mod:`grammar.rows`), and a second hour on the tables the first left.
* Overlap check (§4.2.4) of the whole table by product automata, beside a brute-force
  baseline: every compacted string of up to 4 tokens over the table's tokens tested with
  ``re`` against every pair.
"""

import itertools
import re
import time
from dataclasses import dataclass

import numpy as np

from grammar.recognizer import load_actions
from doodle.core.tokens import CODES, Token
from grammar.automata import sample
from grammar.library import compile_library, overlaps
from grammar.matcher import Matcher
from library.manifest import builtin

TOKENS_PER_SECOND = 3.0  # a brisk doodle: a token every ~0.3 s


def hour_of_tokens(compiled, rng):
    names, out = compiled.library.names, []
    alphabet = sorted(CODES)
    while len(out) < 3600 * TOKENS_PER_SECOND:
        words = sample(compiled.dfas[int(rng.integers(len(names)))], rng)
        words = [alphabet[int(rng.integers(len(alphabet)))] if rng.random() < 0.1 else w for w in words]
        out += words + ["T_STILL"]
    out = [w for i, w in enumerate(out) if i == 0 or w != out[i - 1]]
    return [Token(w, 30 * i, 30 * i + 30) for i, w in enumerate(out)]


@dataclass(frozen=True)
class _Indexed:
    first: int
    token: Token


def regex_of(expression):
    letter = {name: chr(0x100 + code) for name, code in CODES.items()}
    return re.compile(re.sub(r"[A-Z][A-Z_]*", lambda m: letter[m.group()], expression).replace(" ", ""))


def per_token(push, tokens) -> tuple[np.ndarray, np.ndarray]:
    """Seconds of CPU time (this thread) and of wall-clock time of ``push`` per token."""
    cpu, wall = np.empty(len(tokens)), np.empty(len(tokens))
    thread, clock = time.thread_time, time.perf_counter
    for i, tok in enumerate(tokens):
        c0, w0 = thread(), clock()
        push(tok)
        wall[i], cpu[i] = clock() - w0, thread() - c0
    return cpu * 1e6, wall * 1e6


def summary(cpu, wall) -> str:
    return (f"CPU mean {cpu.mean():6.1f} µs  p50 {np.percentile(cpu, 50):5.1f} µs  p99 {np.percentile(cpu, 99):6.1f} µs"
            f"   (wall mean {wall.mean():6.1f} µs, p50 {np.percentile(wall, 50):5.1f} µs)")


def main(runs: int = 3) -> None:
    start = time.perf_counter()
    compiled = load_actions()
    compile_s = time.perf_counter() - start
    auto = compiled.automaton()
    tokens = hour_of_tokens(compiled, np.random.default_rng(0))
    print(f"Matcher ({len(compiled.library.names)} actions, {auto.n} DFA states; library compiled in {compile_s:.2f} s)")
    print("  per token, CPU time of this thread (on a machine shared with other jobs wall-clock time adds "
          f"theirs); median of {runs} runs, the Matcher's tables fresh each run")

    measured, segments = [], []
    for _ in range(runs):
        compiled = load_actions()  # fresh tables: the rows met are interned as the hour goes
        matcher, found = Matcher(compiled.automaton()), []
        cpu, wall = per_token(lambda tok: found.extend(matcher.push(tok)), tokens)
        measured.append((cpu, wall))
        segments = found + matcher.close()
    cpu, wall = sorted(measured, key=lambda m: m[0].mean())[len(measured) // 2]
    print(f"  one hour of tokens: {len(tokens):,} tokens → {len(segments):,} segments")
    print(f"  streaming Matcher:           {summary(cpu, wall)}   (target: mean ≤ 30 µs)")
    matcher = Matcher(compiled.automaton())
    again = per_token(matcher.push, hour_of_tokens(compiled, np.random.default_rng(1)))
    print(f"    a second hour, same tables: {summary(*again)}")

    # naive baseline: re over the whole current prefix, every action, every token
    letter = {name: chr(0x100 + code) for name, code in CODES.items()}
    patterns = [regex_of(a.expression) for a in compiled.library.actions]
    bounds = {s.first for s in segments}
    prefix = ""

    def regex(tok):
        nonlocal prefix
        if tok.first in bounds:
            prefix = ""
        prefix += letter[tok.token.name]
        for p in patterns:
            p.fullmatch(prefix)

    base = sorted((per_token(regex, [_Indexed(i, t) for i, t in enumerate(tokens)]) for _ in range(runs)),
                  key=lambda m: m[0].mean())[runs // 2]
    print(f"  baseline, re over the prefix: {summary(*base)}   (exact matching only)")

    clock = time.perf_counter
    lib = builtin()
    t0 = clock()
    table = compile_library(lib)
    found = overlaps(table)
    overlap_s = clock() - t0
    lib = table.library  # the recognisable actions (clip-only ones have no expression)
    pairs = len(lib.actions) * (len(lib.actions) - 1) // 2
    print(f"  overlap check of the whole table (compile + {pairs} product automata): {overlap_s:.2f} s, "
          f"{len(found)} overlapping pairs (target ≤ 2 s)")
    used = sorted({w for a in lib.actions for w in re.findall(r"[A-Z][A-Z_]*", a.expression)})
    t0 = clock()
    strings = ["".join(letter[w] for w in s) for n in range(1, 5) for s in itertools.product(used, repeat=n)
               if all(a != b for a, b in zip(s, s[1:]))]
    accepted = [{s for s in strings if p.fullmatch(s)} for p in patterns]
    brute = sum(1 for i in range(len(patterns)) for j in range(i + 1, len(patterns)) if accepted[i] & accepted[j])
    brute_s = clock() - t0
    print(f"  baseline, brute force over {len(strings):,} strings of ≤ 4 tokens with re: {brute_s:.2f} s, "
          f"{brute} overlapping pairs found (misses longer witnesses)")


if __name__ == "__main__":
    main()
