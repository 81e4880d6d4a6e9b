"""Real HTC Vive recordings (../shared/data/vive-gestures): load, tokenise, read sensibly."""

import numpy as np

from doodle.input.csvimport import read_csv
from doodle.input.segmenter import tokenize_doodle


def test_every_recording_loads_and_tokenises(vive_files):
    for path in vive_files:
        doodle = read_csv(path, convention="unity")
        assert doodle.names == ["c0", "c1"], path
        tokens = tokenize_doodle(doodle)
        for name, toks in tokens.items():
            assert toks, f"{path} {name}: no tokens"
            assert toks[0].start == 0 and toks[-1].end == len(doodle.t)
            assert all(a.end == b.start and a.name != b.name for a, b in zip(toks, toks[1:]))


def test_uppercut_rises(vive_files):
    """Readable tokens on real data: a right uppercut's striking controller goes up in its own
    frame (a translation token with Y, not N_Y) in at least 80 % of the takes."""
    def moving_tokens(path, track):
        doodle = read_csv(path, convention="unity")
        return [k.name for k in tokenize_doodle(doodle)[track] if k.name.startswith("T_") and k.name != "T_STILL"]

    ups = [f for f in vive_files if f.parent.name == "uppercut_right"]
    assert ups
    rising = sum(any("_Y" in n and "N_Y" not in n for n in moving_tokens(f, "c0")) for f in ups)
    assert rising >= 0.8 * len(ups)



def test_unity_forward_left_up_reads_forward_left_up(tmp_path):
    """A controller at rest orientation moving forward (+z), left (-x) and up (+y) in Unity
    coordinates gives the tokens T_Z, T_X and T_Y: forward, left and up in ours."""
    rate, rows, t, pos = 90.0, [], 0.0, np.zeros(3)
    segments = [((0, 0, 0), 0.5), ((0, 0, 1), 0.6), ((0, 0, 0), 0.4), ((-1, 0, 0), 0.6), ((0, 0, 0), 0.4),
                ((0, 1, 0), 0.6), ((0, 0, 0), 0.5)]
    for direction, duration in segments:
        n = int(duration * rate)
        for i in range(n):
            speed = 0.3 * np.sin(np.pi * (i + 0.5) / n)  # a smooth stroke
            pos = pos + np.array(direction) * speed / rate
            rows.append(f"{t:.6f},{pos[0]:.6f},{pos[1]:.6f},{pos[2]:.6f},0,0,0,1")
            t += 1 / rate
    path = tmp_path / "unity.csv"
    path.write_text("t,c0_px,c0_py,c0_pz,c0_qx,c0_qy,c0_qz,c0_qw\n" + "\n".join(rows) + "\n")
    tokens = tokenize_doodle(read_csv(path, convention="unity"))["c0"]
    assert [k.name for k in tokens] == ["T_STILL", "T_Z", "T_STILL", "T_X", "T_STILL", "T_Y", "T_STILL"]
