"""The recorder: the loop used for SteamVR, run here on synthetic and fake sources with a fake
clock — what it writes, how it paces itself, live recognition, triggers, lost tracking, Ctrl-C,
kill -9, and the missing-SteamVR path."""

import argparse
import os
import signal
import subprocess
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from doodle.input.conventions import to_ours
from doodle.core.errors import DoodleError
from doodle.input.loader import load
from doodle.core.model import Doodle
from grammar.recognizer import load_actions, recognize
from doodle.app.recorder import record
from doodle.input.sources import OpenVRSource, ReplaySource, SyntheticSource, pose_from_matrix
from doodle.synth.strokes import lost_tracking, perform

REPO = Path(__file__).resolve().parents[1]
JUMP = ["T_STILL", "T_Y", "T_Y_Z", "T_N_Y_Z", "T_N_Y", "T_STILL"]


@pytest.fixture(scope="module")
def compiled():
    return load_actions()


@pytest.fixture(scope="module")
def automaton(compiled):
    return compiled


class FakeClock:
    """``clock`` and ``sleep`` for the recorder: sleeping advances time at once."""

    def __init__(self, start=100.0):
        self.now, self.sleeps, self.woke = start, [], []

    def clock(self):
        return self.now

    def sleep(self, seconds):
        self.sleeps.append(seconds)
        self.now += seconds
        self.woke.append(self.now)


def run(source, path, automaton, **kw):
    fake = FakeClock()
    events = []
    result = record(source, path, clock=fake.clock, sleep=fake.sleep, compiled=automaton,
                    on_event=lambda kind, payload: events.append((kind, payload)), **kw)
    return result, events, fake


def two_tracks(loss=(1.0, 1.2)):
    c0 = perform(JUMP, seed=1)
    c1 = lost_tracking(perform(["T_STILL", "T_Y", "T_N_Y", "T_STILL"], seed=2, name="c1"), *loss)
    n = min(len(c0), len(c1))
    cut = [type(tr)(tr.name, c0.t[:n], tr.p[:n], tr.q[:n], tr.valid[:n], role, serial)
           for tr, role, serial in ((c0, "right_hand", "LHR-1"), (c1, "left_hand", ""))]
    return Doodle(tuple(cut), 90.0, "synthetic")


# --------------------------------------------------------------------------- the file


def test_file_holds_the_source_samples(tmp_path, automaton):
    doodle = two_tracks()
    path = tmp_path / "take.doodle"
    result, events, _ = run(SyntheticSource(doodle), path, automaton)
    loaded = load(path)
    assert result.samples == len(doodle.t) == len(loaded.t) and result.reason == "end"
    assert result.duration == pytest.approx(doodle.t[-1] - doodle.t[0])
    assert [(tr.name, tr.role, tr.serial) for tr in loaded.tracks] == [("c0", "right_hand", "LHR-1"),
                                                                       ("c1", "left_hand", "")]
    np.testing.assert_allclose(loaded.t, doodle.t - doodle.t[0], atol=1e-6)
    for want, got in zip(doodle.tracks, loaded.tracks):
        np.testing.assert_array_equal(got.valid, want.valid)
        np.testing.assert_allclose(got.p[got.valid], want.p[want.valid], atol=1e-6)
        np.testing.assert_allclose(got.q[got.valid], want.q[want.valid], atol=2e-6)
    assert (~loaded.tracks[1].valid).sum() > 10  # the lost rows are kept, flagged
    kinds = [k for k, _ in events]
    assert kinds[0] == "started" and kinds[-1] == "stopped"
    lost = [p for k, p in events if k == "lost"]
    found = [p for k, p in events if k == "found"]
    assert [p["track"] for p in lost] == ["c1"] and lost[0]["error"] is None
    assert lost[0]["t"] == pytest.approx(1.0, abs=0.02)
    assert [p["track"] for p in found] == ["c1"] and found[0]["restarted"] is False
    assert found[0]["gap"] == pytest.approx(0.2, abs=0.03)


def test_what_is_loaded_before_recording_is_left_out_of_garbage_collection(tmp_path, automaton):
    """A full collection scans every object the process holds (the library, the modules):
    tens of milliseconds in which no thread runs and the source is not polled. While
    recording, what was loaded before is frozen out of collection; afterwards it is not."""
    import gc

    during, fake = [], FakeClock()
    record(SyntheticSource(two_tracks()), tmp_path / "take.doodle", clock=fake.clock, sleep=fake.sleep,
           compiled=automaton,
           on_event=lambda kind, payload: during.append(gc.get_freeze_count()) if kind == "started" else None)
    assert during and during[0] > 1000 and gc.get_freeze_count() == 0


def test_replay_source_rerecords_a_file(tmp_path, automaton):
    first, second = tmp_path / "a.doodle", tmp_path / "b.doodle"
    run(SyntheticSource(two_tracks()), first, automaton)
    run(ReplaySource(first), second, automaton)
    a, b = load(first), load(second)
    np.testing.assert_allclose(b.t, a.t, atol=1e-6)
    for x, y in zip(a.tracks, b.tracks):
        np.testing.assert_array_equal(x.valid, y.valid)
        np.testing.assert_allclose(x.p[x.valid], y.p[y.valid], atol=1e-6)


def test_an_existing_file_is_kept_unless_overwrite(tmp_path, automaton):
    path = tmp_path / "take.doodle"
    path.write_text("precious")
    with pytest.raises(DoodleError, match="already exists"):
        run(SyntheticSource(two_tracks()), path, automaton)
    assert path.read_text() == "precious"
    run(SyntheticSource(two_tracks()), path, automaton, overwrite=True)
    assert len(load(path).t) > 100


# --------------------------------------------------------------------------- pacing


def test_sleeps_until_each_tick(tmp_path, automaton):
    doodle = two_tracks()
    fake = FakeClock()
    reads = []

    class Stalling(SyntheticSource):
        def read(self):
            reads.append(fake.now)
            if len(reads) == 40:
                fake.now += 0.1  # a stall of 9 ticks: skipped, not caught up in a burst
            return super().read()

    record(Stalling(doodle), tmp_path / "paced.doodle", clock=fake.clock, sleep=fake.sleep, compiled=automaton)
    period = 1 / 90
    assert len(reads) == len(doodle.t) + 1  # the last read says the source ended
    assert all(s > 0 for s in fake.sleeps)
    # before the stall: asleep until each tick 100 + k/90, one read per tick
    np.testing.assert_allclose(np.array(fake.woke[:39]) - 100.0, np.arange(1, 40) * period, rtol=1e-9)
    np.testing.assert_allclose(reads[:40], 100.0 + np.arange(40) * period, rtol=1e-12)
    after = np.array(reads[40:])
    assert after[0] == pytest.approx(reads[39] + 0.1, abs=1e-9)  # the next read at once, then one per tick
    np.testing.assert_allclose(np.diff(after), period, rtol=1e-9)


def test_slow_recognition_leaves_no_hole_in_a_live_recording(tmp_path, automaton, monkeypatch):
    """A live source gives only the pose of the moment (SteamVR): the recorder must poll it on
    every tick, however long recognising a frame takes (deciding a learned action can take a
    few tenths of a second). Recognition stalls here for 0.3 s on one frame, on the real clock;
    the frames that waited meanwhile are recognised without working out provisional labels,
    but for the newest (catching up)."""
    from bench.replay_latency import OfTheMoment
    from grammar import recognizer

    doodle = two_tracks()
    slow, pushes = 0.3, []
    push = recognizer.Live.push

    def stalling(self, t, poses, labels=True):
        pushes.append((t, labels))
        if len(pushes) == 30:
            time.sleep(slow)
        return push(self, t, poses, labels)

    monkeypatch.setattr(recognizer.Live, "push", stalling)

    result = record(OfTheMoment(doodle, 60), tmp_path / "live.doodle", compiled=automaton)
    t = load(tmp_path / "live.doodle").t
    assert len(pushes) == result.samples == len(t)  # every frame recorded was recognised
    assert np.diff(t).max() < slow / 2  # polled on every tick meanwhile: no hole of the stall's length
    waited = [k for k, (_, labels) in enumerate(pushes) if not labels]
    assert waited and waited[0] == 30 and len(waited) >= 10 and pushes[-1][1]


# --------------------------------------------------------------------------- live recognition


def test_actions_are_reported_as_they_are_recognised(tmp_path, compiled, automaton):
    doodle = Doodle((perform(JUMP, seed=4),), 90.0, "synthetic")
    path = tmp_path / "jump.doodle"
    result, events, _ = run(SyntheticSource(doodle), path, automaton)
    actions = [p for k, p in events if k == "action"]
    assert [a["action"] for a in actions] == ["Idle", "Jump", "Idle"]
    jump = actions[1]
    # one 0.4 s pause, then four 0.3 s strokes (±10 % each)
    assert jump["start"] == pytest.approx(0.4, abs=0.1) and jump["end"] == pytest.approx(1.6, abs=0.15)
    assert jump["exact"] and jump["at"] >= jump["end"]
    assert result.actions == {"c0": [(a["action"], a["start"], a["end"]) for a in actions]}
    # live recognition gives what the batch path gives on the written file
    loaded = load(path)
    tokens, segments = recognize(loaded, compiled)["c0"]
    t = loaded.t
    assert [s.action for s in segments if s.action != "unknown"] == [a for a, _, _ in result.actions["c0"]]
    np.testing.assert_allclose([t[s.start] for s in segments if s.action != "unknown"],
                               [s for _, s, _ in result.actions["c0"]], atol=1e-6)
    final = [p["token"] for k, p in events if k == "token" and p["final"]]
    assert final == [k.name for k in tokens]
    shown = [p["token"] for k, p in events if k == "token" and not p["final"]]
    assert shown == final  # each token shown once while in progress, before it is final


def test_a_long_loss_restarts_recognition_without_crashing(tmp_path, automaton):
    words = JUMP + ["T_STILL"] * 5 + ["T_Y", "T_N_Y", "T_STILL"]  # a jump, a long pause, a stomp
    track = lost_tracking(perform(words, seed=1), 2.4, 3.6)  # 1.2 s lost > max_gap 0.5 s
    path = tmp_path / "lost.doodle"
    result, events, _ = run(SyntheticSource(Doodle((track,), 90.0, "synthetic")), path, automaton)
    loaded = load(path)
    assert result.samples == len(track) == len(loaded.t)
    np.testing.assert_array_equal(loaded.tracks[0].valid, track.valid)
    lost = [p for k, p in events if k == "lost"]
    assert lost[0]["error"] is None and lost[0]["t"] == pytest.approx(2.4, abs=0.02)
    assert "lost tracking for 1.2" in lost[1]["error"] and lost[1]["t"] == pytest.approx(3.6, abs=0.02)
    found = [p for k, p in events if k == "found"]
    assert len(found) == 1 and found[0]["restarted"] and found[0]["gap"] == pytest.approx(1.2, abs=0.03)
    names = [a for a, _, _ in result.actions["c0"]]
    assert "Jump" in names and "Stomp" in names
    assert names.index("Jump") < names.index("Stomp")
    stomp = result.actions["c0"][names.index("Stomp")]
    assert stomp[1] >= 3.6 - 0.02  # recognised in the samples after the loss


def test_a_track_lost_until_the_end(tmp_path, automaton):
    track = lost_tracking(perform(JUMP + ["T_STILL"] * 3, seed=5), 2.0, 99.0)
    result, events, _ = run(SyntheticSource(Doodle((track,), 90.0, "synthetic")), tmp_path / "end.doodle", automaton)
    assert [a for a, _, _ in result.actions["c0"]][:2] == ["Idle", "Jump"]
    assert [k for k, _ in events].count("found") == 0 and result.samples == len(track)


# --------------------------------------------------------------------------- start and stop


def test_trigger_starts_and_stops(tmp_path, automaton):
    doodle = two_tracks()
    t = doodle.t
    path = tmp_path / "trig.doodle"
    result, events, _ = run(SyntheticSource(doodle, triggers=[0.3, 1.1]), path, automaton, wait_for_trigger=True)
    first, stop = np.searchsorted(t, 0.3), np.searchsorted(t, 1.1)
    loaded = load(path)
    assert result.reason == "trigger" and result.samples == stop - first == len(loaded.t)
    np.testing.assert_allclose(loaded.t, t[first:stop] - t[first], atol=1e-6)
    np.testing.assert_allclose(loaded.tracks[0].p, doodle.tracks[0].p[first:stop], atol=1e-6)
    assert events[0][0] == "started" and events[-1] == ("stopped", {"t": result.duration, "reason": "trigger",
                                                                     "samples": result.samples})


def test_no_trigger_press_records_nothing(tmp_path, automaton):
    path = tmp_path / "never.doodle"
    with pytest.raises(DoodleError, match="trigger was never pressed"):
        run(SyntheticSource(two_tracks()), path, automaton, wait_for_trigger=True)
    assert not path.exists()


def test_max_seconds(tmp_path, automaton):
    doodle = two_tracks()
    result, _, _ = run(SyntheticSource(doodle), tmp_path / "short.doodle", automaton, max_seconds=1.0)
    assert result.reason == "seconds" and result.samples == np.sum(doodle.t - doodle.t[0] <= 1.0)
    assert result.duration <= 1.0


def test_ctrl_c_ends_the_recording_cleanly(tmp_path, automaton):
    class Interrupted(SyntheticSource):
        def read(self):
            if self._i == 120:
                raise KeyboardInterrupt
            return super().read()

    path = tmp_path / "ctrlc.doodle"
    result, events, _ = run(Interrupted(Doodle((perform(JUMP, seed=4),), 90.0, "synthetic")), path, automaton)
    assert result.reason == "interrupted" and result.samples == 120 == len(load(path).t)
    assert [a for a, _, _ in result.actions["c0"]][:2] == ["Idle", "Jump"]  # the actions in flight are flushed
    assert events[-1][0] == "stopped"


def test_the_demo_scene_is_recognised(tmp_path, automaton):
    from doodle.app.cli.record import _open_source

    source = _open_source(argparse.Namespace(source="synthetic", trigger=False))
    result, _, _ = run(source, tmp_path / "demo.doodle", automaton)
    assert [a for a, _, _ in result.actions["c0"]] == ["Idle", "Side Walk Left", "Idle", "Walk", "Idle", "Jump",
                                                        "Idle", "Walk", "Idle", "Stomp", "Idle"]


# --------------------------------------------------------------------------- kill -9

CHILD = """
import sys
sys.path.insert(0, sys.argv[1])
from doodle.app.recorder import record
from doodle.input.sources import SyntheticSource
from doodle.synth.strokes import stroke, synth_doodle

doodle = synth_doodle([stroke("T_STILL", 0.5), stroke("T_Z", 4.0, 0.4), stroke("T_STILL", 1.5)], seed=3)

def show(kind, payload):
    if kind == "started":
        print("started", flush=True)

record(SyntheticSource(doodle), sys.argv[2], on_event=show)
print("finished", flush=True)
"""


def test_kill_9_loses_at_most_about_a_second(tmp_path):
    path = tmp_path / "killed.doodle"
    proc = subprocess.Popen([sys.executable, "-c", CHILD, str(REPO), str(path)], stdout=subprocess.PIPE, text=True)
    try:
        assert proc.stdout.readline().strip() == "started"  # blocks until the first frame is written
        started = time.monotonic()
        time.sleep(2.5)
        assert proc.poll() is None, "the recorder ended on its own"
        os.kill(proc.pid, signal.SIGKILL)
        killed = time.monotonic() - started
        proc.wait(10)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(10)
    assert proc.returncode == -signal.SIGKILL
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the kill may cut the last line
        loaded = load(path)
    last = float(loaded.t[-1])
    assert killed - last <= 1.3, f"killed at {killed:.2f} s, the file ends at {last:.2f} s"
    assert len(loaded.t) == pytest.approx(last * 90 + 1, abs=2)  # no hole before the cut


# --------------------------------------------------------------------------- SteamVR


def _no_steamvr():
    try:
        OpenVRSource().close()
    except DoodleError:
        return
    pytest.skip("SteamVR is running here")


def test_missing_steamvr_is_one_clear_line(capfd):
    _no_steamvr()
    capfd.readouterr()
    began = time.monotonic()
    with pytest.raises(DoodleError) as err:
        OpenVRSource()
    assert time.monotonic() - began < 2.0  # fails at once, not after a timeout (generous bound)
    message = str(err.value)
    assert "SteamVR is not running" in message and "doodle replay FILE" in message and "\n" not in message
    assert capfd.readouterr().err == ""  # the C library's own line went into the message


def test_record_command_without_steamvr_leaves_no_file(tmp_path, capfd):
    _no_steamvr()
    from doodle.app.cli.main import build_parser

    parser = build_parser(["record"])
    path = tmp_path / "live.doodle"
    args = parser.parse_args(["record", "-o", str(path), "--seconds", "5", "--trigger"])
    with pytest.raises(DoodleError, match="SteamVR is not running.*doodle replay"):
        args.run(args)
    assert not path.exists() and not list(tmp_path.iterdir())
    assert capfd.readouterr().err == ""


def test_record_command_with_the_synthetic_source(tmp_path, capsys, monkeypatch, compiled):
    import grammar.recognizer
    from doodle.app.cli.main import build_parser

    monkeypatch.setattr(grammar.recognizer, "load_actions", lambda *a: compiled)
    parser = build_parser(["record"])
    path = tmp_path / "synthetic.doodle"
    args = parser.parse_args(["record", "-o", str(path), "--source", "synthetic", "--seconds", "0.6"])
    assert args.run(args) == 0
    out = capsys.readouterr().out
    assert "Idle" in out and f"wrote {path}" in out
    assert 0.5 < load(path).t[-1] <= 0.6
    with pytest.raises(DoodleError, match="already exists"):
        args.run(args)


def test_openvr_poses_are_converted_into_our_frame():
    r = Rotation.from_euler("xyz", [0.3, -0.5, 1.1])
    m = np.hstack([r.as_matrix(), [[0.1], [1.2], [-0.4]]])
    p, q = pose_from_matrix(m)
    want_p, want_q = to_ours([0.1, 1.2, -0.4], r.as_quat(), "openvr")
    np.testing.assert_allclose(p, [-0.1, 1.2, 0.4])
    assert abs(np.dot(q, want_q)) == pytest.approx(1.0)
    # a controller pointing along its own -z (OpenVR forward) points along our +z: its figurine front
    yaw = Rotation.from_euler("y", 0.4).as_matrix()
    _, q = pose_from_matrix(np.hstack([yaw, np.zeros((3, 1))]))
    front_openvr = yaw @ [0.0, 0.0, -1.0]
    np.testing.assert_allclose(Rotation.from_quat(q).apply([0.0, 0.0, 1.0]), front_openvr * [-1, 1, -1], atol=1e-12)


class FakeSystem:
    """The part of ``openvr.IVRSystem`` the source uses, filling the real ctypes structs."""

    def __init__(self, openvr):
        self.vr = openvr
        self.classes = {1: openvr.TrackedDeviceClass_HMD, 3: openvr.TrackedDeviceClass_Controller,
                        4: openvr.TrackedDeviceClass_Controller, 6: openvr.TrackedDeviceClass_GenericTracker}
        self.roles = {3: openvr.TrackedControllerRole_LeftHand, 4: openvr.TrackedControllerRole_RightHand}
        self.frame, self.pressed = 0, {4: [False, True, True, False, True]}

    def getTrackedDeviceClass(self, i):
        return self.classes.get(i, self.vr.TrackedDeviceClass_Invalid)

    def isTrackedDeviceConnected(self, i):
        return i in self.classes

    def getControllerRoleForTrackedDeviceIndex(self, i):
        return self.roles.get(i, self.vr.TrackedControllerRole_Invalid)

    def getStringTrackedDeviceProperty(self, i, prop):
        assert prop == self.vr.Prop_SerialNumber_String
        return f"LHR-{i} X"

    def getDeviceToAbsoluteTrackingPose(self, origin, predict, poses):
        assert origin == self.vr.TrackingUniverseStanding and predict == 0
        for i in (3, 4, 6):
            pose = poses[i]
            for r in range(3):
                for c in range(4):
                    shift = 0.1 * i + 0.01 * self.frame if c == 3 else 0.0  # identity rotation, moving
                    pose.mDeviceToAbsoluteTracking.m[r][c] = float(r == c) + shift
            pose.bPoseIsValid = not (i == 6 and self.frame == 2)
            pose.eTrackingResult = (self.vr.TrackingResult_Running_OutOfRange if i == 3 and self.frame == 1
                                    else self.vr.TrackingResult_Running_OK)
        self.frame += 1
        return poses

    def getControllerState(self, i):
        state = self.vr.VRControllerState_t()
        seq = self.pressed.get(i, [])
        if self.frame - 1 < len(seq) and seq[self.frame - 1]:
            state.ulButtonPressed = 1 << self.vr.k_EButton_SteamVR_Trigger
        return i in self.roles, state


def test_openvr_source_with_a_fake_runtime(monkeypatch):
    import openvr

    shutdowns = []
    monkeypatch.setattr(openvr, "init", lambda kind: FakeSystem(openvr))
    monkeypatch.setattr(openvr, "shutdown", lambda: shutdowns.append(1))
    fake = FakeClock(50.0)
    source = OpenVRSource(clock=fake.clock)
    assert source.tracks == [("c0", "right_hand", "LHR-4_X"), ("c1", "left_hand", "LHR-3_X"),
                             ("c2", "tracker", "LHR-6_X")]
    assert source.rate == 90.0 and source.device == "vive-controller"
    frames = []
    for _ in range(5):
        frames.append(source.read())
        fake.now += 0.02
    assert [f.t for f in frames] == pytest.approx([0.0, 0.02, 0.04, 0.06, 0.08])
    assert [f.trigger for f in frames] == [False, True, False, False, True]  # press edges only
    assert [[ok for _, _, ok in f.poses] for f in frames[:3]] == [[True] * 3, [True, False, True], [True, True, False]]
    p, q, _ = frames[0].poses[0]
    np.testing.assert_allclose(p, [-0.4, 0.4, -0.4], atol=1e-6)  # OpenVR (0.4, 0.4, 0.4) in our frame
    np.testing.assert_allclose(q, [0, 0, 0, 1], atol=1e-7)
    assert np.isnan(frames[1].poses[1][0]).all()
    source.close()
    source.close()
    assert shutdowns == [1]
