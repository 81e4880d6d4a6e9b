"""`doodle replay`: the live path (streaming Segmenter and Matcher, sample by sample) gives
what the batch path gives, with latencies, at the pace asked for."""

from pathlib import Path

import pytest

from doodle.app.cli.main import main
from doodle.input.loader import load
from grammar.recognizer import load_actions, recognize
from doodle.app.replay import replay
from doodle.synth.strokes import lost_tracking

DEMO = Path(__file__).resolve().parents[1] / "examples" / "demo.doodle"


def test_streaming_replay_equals_batch_recognition():
    doodle = load(DEMO)
    compiled = load_actions()
    replayed = replay(doodle, compiled)
    found, costs = replayed.found, replayed.costs
    _, batch = recognize(doodle, compiled)["c0"]
    t = doodle.t
    assert [(r.action, r.start) for r in found] == [(s.action, float(t[s.start])) for s in batch if s.action != "unknown"]
    assert all(r.latency >= 0 for r in found) and len(costs) == len(t)


def test_two_tracks_and_lost_tracking_stream():
    from doodle.core.model import Doodle

    doodle = load(DEMO)
    tr = doodle.tracks[0]
    second = lost_tracking(tr, 2.0, 2.3)
    two = Doodle((tr, type(tr)("c1", second.t, second.p + 1.0, second.q, second.valid)), doodle.rate)
    found = replay(two, load_actions()).found
    assert {r.track for r in found} == {"c0", "c1"}
    assert [r.action for r in found if r.track == "c0"] == [r.action for r in found if r.track == "c1"]


def test_pacing_follows_the_clock():
    doodle = load(DEMO)
    now = [0.0]
    waits = []

    def clock():
        return now[0]

    def sleep(s):
        waits.append(s)
        now[0] += s

    replay(doodle, load_actions(), speed=2.0, clock=clock, sleep=sleep)
    assert min(waits) > 0 and sum(waits) == pytest.approx(doodle.t[-1] / 2.0, rel=1e-6)


def test_replay_command(capsys):
    assert main(["replay", str(DEMO), "--speed", "0"]) == 0
    out = capsys.readouterr().out
    assert "Jump" in out and "latency" in out and "p99" in out
    assert main(["replay", str(DEMO), "--speed", "-1"]) == 1
    assert "--speed must be" in capsys.readouterr().err
    assert main(["replay", "missing.doodle"]) == 1
