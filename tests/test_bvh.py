"""BVH reader and writer (retarget.bvh): round trips on the real mocap files, agreement with
the independent reader bvhio, channel orders, exact frame time, and clear errors."""

import os
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from doodle.core.errors import DoodleError
from retarget.bvh import _format_rows, format_bvh, guess_unit, read_bvh, read_bvh_with_unit, write_bvh
from retarget.skeleton import end_site_positions, forward_kinematics

MOCAP = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "mocap"
ALL_BVH = sorted(MOCAP.rglob("*.bvh")) if MOCAP.is_dir() else []


def _id(path: Path) -> str:
    return str(path.relative_to(MOCAP))


def _sampled(motion, count=8):
    """The motion at ``count`` frames spread over the clip (first and last included)."""
    idx = np.unique(np.linspace(0, motion.frames - 1, count).round().astype(int))
    return replace(motion, translations=motion.translations[idx], rotations=motion.rotations[idx]), idx


# --------------------------------------------------------------------------- real files


@pytest.mark.skipif(not ALL_BVH, reason=f"mocap files not found under {MOCAP}")
@pytest.mark.parametrize("path", ALL_BVH, ids=_id)
def test_round_trip_keeps_world_positions(path, tmp_path):
    motion, unit = read_bvh_with_unit(path)
    assert unit == 0.01  # Bandai and DeepMimic are in centimetres
    out = tmp_path / "out.bvh"
    write_bvh(out, motion, unit=unit)
    again, unit2 = read_bvh_with_unit(out)
    assert unit2 == unit
    sk, sk2 = motion.skeleton, again.skeleton
    assert sk2.names == sk.names and sk2.channels == sk.channels
    np.testing.assert_array_equal(sk2.parents, sk.parents)
    np.testing.assert_allclose(sk2.offsets, sk.offsets, atol=1e-6 * unit)
    assert sk2.end_sites.keys() == sk.end_sites.keys()
    for j in sk.end_sites:
        np.testing.assert_allclose(sk2.end_sites[j], sk.end_sites[j], atol=1e-6 * unit)
    assert again.frames == motion.frames
    assert again.frame_time == motion.frame_time  # exactly
    a, _ = _sampled(motion)
    b, _ = _sampled(again)
    pa, pb = forward_kinematics(a)[0], forward_kinematics(b)[0]
    np.testing.assert_allclose(pb, pa, atol=1e-4 * unit, rtol=0)


def _bvhio_selection():
    picks = []
    for folder, count in (("bandai/dataset-1", 3), ("bandai/dataset-2", 1), ("deepmimic", 4)):
        files = sorted((MOCAP / folder).glob("*.bvh"), key=lambda p: (p.stat().st_size, p.name))
        picks += files[:count]
    picks.append(MOCAP / "deepmimic" / "backflip.bvh")
    return [p for p in dict.fromkeys(picks) if p.exists()]


@pytest.mark.skipif(not ALL_BVH, reason=f"mocap files not found under {MOCAP}")
@pytest.mark.parametrize("path", _bvhio_selection() if ALL_BVH else [], ids=_id)
def test_forward_kinematics_matches_bvhio(path):
    bvhio = pytest.importorskip("bvhio")
    motion = read_bvh(path, unit=1.0)  # file units, like bvhio
    sampled, frames = _sampled(motion, 4)
    ours = forward_kinematics(sampled)[0]
    root = bvhio.readAsHierarchy(str(path))
    layout = [joint for joint, _, _ in root.layout()]
    assert [j.Name for j in layout] == list(motion.skeleton.names)
    for k, frame in enumerate(frames):
        root.loadPose(int(frame))
        theirs = np.array([list(j.PositionWorld) for j in layout], dtype=float)
        np.testing.assert_allclose(ours[k], theirs, atol=1e-3, rtol=0, err_msg=f"frame {frame}")


@pytest.mark.skipif(not ALL_BVH, reason=f"mocap files not found under {MOCAP}")
def test_bandai_layout_and_position_channels():
    path = MOCAP / "bandai" / "dataset-1" / "dataset-1_walk_normal_001.bvh"
    motion = read_bvh(path)
    sk = motion.skeleton
    assert len(sk) == 22 and sk.names[0] == "joint_Root"
    assert all(c == ("Xposition", "Yposition", "Zposition", "Zrotation", "Xrotation", "Yrotation")
               for c in sk.channels)
    assert motion.frame_time == 0.0333333 and motion.frames == 195
    # The position channels replace the OFFSET: Hips carries the body's translation, the
    # joints below it repeat their OFFSET (to the file's rounding).
    hips = sk.index("Hips")
    assert np.abs(motion.translations[:, hips] - sk.offsets[hips]).max() > 1.0  # metres
    below = [j for j in range(len(sk)) if j > hips]
    assert np.abs(motion.translations[:, below] - sk.offsets[below]).max() < 1e-6  # metres
    # first motion line: the Hips position channels are -1.71443 90.2704 -407.123 cm
    np.testing.assert_allclose(motion.translations[0, hips], [-0.0171443, 0.902704, -4.07123])


@pytest.mark.skipif(not ALL_BVH, reason=f"mocap files not found under {MOCAP}")
def test_deepmimic_layout_and_end_sites():
    motion = read_bvh(MOCAP / "deepmimic" / "walk.bvh")
    sk = motion.skeleton
    assert sk.channels[0] == ("Xposition", "Yposition", "Zposition", "Zrotation", "Yrotation", "Xrotation")
    assert all(c == ("Zrotation", "Yrotation", "Xrotation") for c in sk.channels[1:])
    assert sk.end_sites and motion.frame_time == 0.033332
    rest = np.broadcast_to(sk.offsets[1:], motion.translations[:, 1:].shape)
    np.testing.assert_array_equal(motion.translations[:, 1:], rest)


# --------------------------------------------------------------------------- synthetic files

MIXED = """\
HIERARCHY
ROOT Hips
{
  OFFSET 1 2 3
  CHANNELS 6 Xposition Yposition Zposition Xrotation Yrotation Zrotation
  JOINT Spine
  {
    OFFSET 0 10 0
    CHANNELS 3 Zrotation Xrotation Yrotation
    JOINT Head
    {
      OFFSET 0 8 1
      CHANNELS 3 Yrotation Zrotation Xrotation
      End Site
      {
        OFFSET 0 5 0
      }
    }
  }
  JOINT Slider
  {
    OFFSET 4 0 0
    CHANNELS 6 Zrotation Yposition Xrotation Zposition Yrotation Xposition
    JOINT Foot
    {
      OFFSET 0 -9 0
      CHANNELS 3 xrotation ZROTATION Yrotation
      End Site
      {
        OFFSET 1 0 0
      }
    }
  }
}
MOTION
Frames: 2
Frame Time: 0.0333333
0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0
0.5 -1.25 2 10 -20 30 15 25 -35 40 -45 50 60 7.5 -70 0.25 80 -1.5 -10 33 -66
"""
MIXED_WIDTH = 21


def _rx(a):
    c, s = np.cos(np.radians(a)), np.sin(np.radians(a))
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def _ry(a):
    c, s = np.cos(np.radians(a)), np.sin(np.radians(a))
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def _rz(a):
    c, s = np.cos(np.radians(a)), np.sin(np.radians(a))
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def _write(tmp_path, text, name="clip.bvh"):
    path = tmp_path / name
    path.write_text(text)
    return path


def test_mixed_channel_orders_match_hand_computed_fk(tmp_path):
    motion = read_bvh(_write(tmp_path, MIXED), unit=1.0)
    sk = motion.skeleton
    assert sk.names == ("Hips", "Spine", "Head", "Slider", "Foot")
    assert list(sk.parents) == [-1, 0, 1, 0, 3]
    assert sk.channels[4] == ("Xrotation", "Zrotation", "Yrotation")  # names are case-insensitive
    v = [0.5, -1.25, 2, 10, -20, 30, 15, 25, -35, 40, -45, 50, 60, 7.5, -70, 0.25, 80, -1.5, -10, 33, -66]
    # Hips: position X Y Z, rotation X Y Z (intrinsic: Rx·Ry·Rz)
    r0 = _rx(v[3]) @ _ry(v[4]) @ _rz(v[5])
    p0 = np.array(v[0:3])
    # Spine: Z X Y
    r1 = r0 @ _rz(v[6]) @ _rx(v[7]) @ _ry(v[8])
    p1 = p0 + r0 @ [0, 10, 0]
    # Head: Y Z X
    r2 = r1 @ _ry(v[9]) @ _rz(v[10]) @ _rx(v[11])
    p2 = p1 + r1 @ [0, 8, 1]
    head_end = p2 + r2 @ [0, 5, 0]
    # Slider: Zrot Ypos Xrot Zpos Yrot Xpos -> rotation Z X Y; the position REPLACES the offset
    r3 = r0 @ _rz(v[12]) @ _rx(v[14]) @ _ry(v[16])
    p3 = p0 + r0 @ [v[17], v[13], v[15]]
    # Foot: X Z Y
    r4 = r3 @ _rx(v[18]) @ _rz(v[19]) @ _ry(v[20])
    p4 = p3 + r3 @ [0, -9, 0]
    foot_end = p4 + r4 @ [1, 0, 0]

    world = forward_kinematics(motion)
    np.testing.assert_allclose(world[0][1], [p0, p1, p2, p3, p4], atol=1e-9)
    for j, r in enumerate([r0, r1, r2, r3, r4]):
        np.testing.assert_allclose(Rotation.from_quat(world[1][1, j]).as_matrix(), r, atol=1e-12)
    ends = end_site_positions(motion, world)
    np.testing.assert_allclose(ends[2][1], head_end, atol=1e-9)
    np.testing.assert_allclose(ends[4][1], foot_end, atol=1e-9)
    # frame 0: rest pose at the root position, the Slider at (0, 0, 0) from its channels
    np.testing.assert_allclose(world[0][0], [[0, 0, 0], [0, 10, 0], [0, 18, 1], [0, 0, 0], [0, -9, 0]], atol=1e-12)


def test_mixed_layout_round_trips(tmp_path):
    motion = read_bvh(_write(tmp_path, MIXED), unit=1.0)
    out = tmp_path / "again.bvh"
    write_bvh(out, motion, unit=1.0)
    text = out.read_text()
    assert "CHANNELS 6 Zrotation Yposition Xrotation Zposition Yrotation Xposition" in text
    assert "CHANNELS 3 Yrotation Zrotation Xrotation" in text
    assert "Frame Time: 0.0333333\n" in text
    again = read_bvh(out, unit=1.0)
    assert again.skeleton.channels == motion.skeleton.channels
    np.testing.assert_allclose(forward_kinematics(again)[0], forward_kinematics(motion)[0], atol=1e-5)
    np.testing.assert_allclose(again.translations, motion.translations, atol=1e-6)
    # the written channel values reproduce the file's (angles within ±180 here)
    line = text.strip().splitlines()[-1].split()
    np.testing.assert_allclose([float(x) for x in line],
                               [float(x) for x in MIXED.strip().splitlines()[-1].split()], atol=1e-5)


def test_frame_time_is_exact(tmp_path):
    motion = read_bvh(_write(tmp_path, MIXED))
    assert motion.frame_time == 0.0333333
    write_bvh(tmp_path / "b.bvh", motion)
    assert read_bvh(tmp_path / "b.bvh").frame_time == 0.0333333
    odd = replace(motion, frame_time=1 / 120)
    write_bvh(tmp_path / "c.bvh", odd)
    assert read_bvh(tmp_path / "c.bvh").frame_time == 1 / 120


def test_units(tmp_path):
    path = _write(tmp_path, MIXED)
    cm, unit = read_bvh_with_unit(path)
    assert unit == 0.01  # rest height 27 file units > 10
    m = read_bvh(path, unit=1.0)
    np.testing.assert_allclose(cm.translations, m.translations * 0.01)
    np.testing.assert_allclose(cm.skeleton.offsets, m.skeleton.offsets * 0.01)
    np.testing.assert_allclose(cm.skeleton.end_sites[2], [0, 0.05, 0])
    np.testing.assert_array_equal(cm.rotations, m.rotations)
    assert guess_unit(m.skeleton) == 0.01
    small = MIXED.replace("OFFSET 0 10 0", "OFFSET 0 0.3 0").replace("OFFSET 0 8 1", "OFFSET 0 0.2 0.01") \
        .replace("OFFSET 0 -9 0", "OFFSET 0 -0.9 0").replace("OFFSET 1 2 3", "OFFSET 0 1 0")
    assert read_bvh_with_unit(_write(tmp_path, small, "m.bvh"))[1] == 1.0
    # writing in centimetres gives back the file's numbers
    write_bvh(tmp_path / "cm.bvh", cm, unit=0.01)
    assert "OFFSET 0 10 0\n" in (tmp_path / "cm.bvh").read_text()


def test_motion_block_formatting_matches_printf():
    rng = np.random.default_rng(2)
    data = np.concatenate([rng.uniform(-500, 500, 300), rng.normal(0, 1e-5, 100),
                           np.arange(-20, 20) * 0.5e-6,  # exact ties in the last digit
                           [0.0, -0.0, 1e-7, -4e-7, 999.9999995, 123456789.25, -2.5, 0.125]]).reshape(-1, 7)
    huge = np.array([[1e300, -2.5, -1e-9, 0.125]])  # beyond int64: the printf fallback
    for block in (data, huge):
        for precision in (0, 3, 6, 9):
            zero = f"{0:.{precision}f}"
            ref = ["".join(" ".join(zero if t == "-" + zero else t for t in (f"%.{precision}f" % v for v in row)))
                   for row in block]
            assert _format_rows(block, precision) == "\n".join(ref) + "\n"



# --------------------------------------------------------------------------- errors


def _line_of(text, needle):
    return next(k + 1 for k, line in enumerate(text.splitlines()) if needle in line)


def _error(tmp_path, text):
    path = _write(tmp_path, text, "bad.bvh")
    with pytest.raises(DoodleError) as info:
        read_bvh(path)
    message = str(info.value)
    assert message.startswith(f"{path}:") and "\n" not in message
    return message


def test_truncated_mid_line(tmp_path):
    text = MIXED[:MIXED.rindex("80 -1.5")]  # cut inside the last frame line
    message = _error(tmp_path, text)
    assert f":{len(text.splitlines())}:" in message and "truncated" in message


def test_truncated_real_file(tmp_path):
    if not ALL_BVH:
        pytest.skip("mocap files not found")
    text = (MOCAP / "bandai" / "dataset-1" / "dataset-1_walk_normal_001.bvh").read_text()
    cut = text[:len(text) * 3 // 5]
    message = _error(tmp_path, cut)
    assert f":{len(cut.splitlines())}:" in message and "truncated" in message
    whole_lines = cut[:cut.rindex("\n") + 1]  # fewer frame lines than Frames: says
    message = _error(tmp_path, whole_lines)
    assert f":{len(whole_lines.splitlines())}:" in message and "truncated" in message and "of 195 frames" in message


def test_wrong_value_count(tmp_path):
    text = MIXED.replace("Frames: 2", "Frames: 3").replace("0.5 -1.25 2 10", "0.5 -1.25 2 10 11") + "0 " * 21 + "\n"
    message = _error(tmp_path, text)
    line = _line_of(text, "0.5 -1.25 2 10 11")
    assert line == len(text.splitlines()) - 1
    assert f":{line}:" in message and f"expected {MIXED_WIDTH}" in message and "22 values" in message


@pytest.mark.parametrize("old, new, needle, words", [
    ("CHANNELS 3 Zrotation Xrotation Yrotation", "CHANNELS 4 Zrotation Xrotation Yrotation Xposition",
     "CHANNELS 4", "3 or 6"),
    ("CHANNELS 3 Zrotation Xrotation Yrotation", "CHANNELS 3 Zrotation Xrotation Yrotatoin",
     "Yrotatoin", "unknown channel name 'Yrotatoin'"),
    ("CHANNELS 3 Zrotation Xrotation Yrotation", "CHANNELS 3 Zrotation Xrotation",
     "CHANNELS 3 Zrotation Xrotation", "says 3 but names 2"),
    ("OFFSET 0 10 0", "OFFSET 0 10", "OFFSET 0 10", "expected 3 numbers"),
    ("OFFSET 0 10 0", "OFFSET 0 ten 0", "OFFSET 0 ten 0", "not 3 numbers"),
    ("JOINT Spine", "JOINT", "JOINT\n", "without a joint name"),
    ("HIERARCHY", "HIERARCHI", "HIERARCHI", "expected HIERARCHY"),
    ("Frames: 2", "Frames: two", "Frames:", "positive whole number"),
    ("Frames: 2", "Frames: 0", "Frames:", "positive whole number"),
    ("Frames: 2\n", "", "Frame Time", "Frames: N"),
    ("Frame Time: 0.0333333", "Frame Time: -0.1", "Frame Time", "positive number"),
    ("Frame Time: 0.0333333\n", "", "0 0 0 0", "Frame Time"),
    ("0.5 -1.25 2 10", "0.5 -1.25 abc 10", "abc", "non-numeric value 'abc'"),
    ("0.5 -1.25 2 10", "0.5 -1.25 nan 10", "nan", "not finite"),
    ("      End Site\n", "      End Sight\n", "End Sight", "expected 'End Site'"),
    ("    OFFSET 0 -9 0\n", "    OFFSET 0 -9 0\n    bogus\n", "bogus", "unexpected token 'bogus'"),
])
def test_bad_input_names_the_line(tmp_path, old, new, needle, words):
    assert old in MIXED
    text = MIXED.replace(old, new, 1)
    message = _error(tmp_path, text)
    if needle.endswith("\n"):
        line = next(k + 1 for k, ln in enumerate(text.splitlines()) if ln.strip() == needle.strip())
    else:
        line = _line_of(text, needle)
    assert f"bad.bvh:{line}:" in message, message
    assert words in message, message


def test_missing_closing_brace(tmp_path):
    lines = MIXED.splitlines()
    k = lines.index("}")  # the root's closing brace
    text = "\n".join(lines[:k] + lines[k + 1:]) + "\n"
    message = _error(tmp_path, text)
    assert f":{_line_of(text, 'MOTION')}:" in message and "missing '}'" in message


def test_missing_opening_brace(tmp_path):
    text = MIXED.replace("  JOINT Slider\n  {\n", "  JOINT Slider\n")
    message = _error(tmp_path, text)
    assert f":{_line_of(text, 'JOINT Slider') + 1}:" in message and "expected '{'" in message


def test_extra_closing_brace(tmp_path):
    text = MIXED.replace("}\nMOTION", "}\n}\nMOTION")
    message = _error(tmp_path, text)
    assert f":{_line_of(text, 'MOTION') - 1}:" in message and "unexpected '}'" in message


def test_empty_and_missing_sections(tmp_path):
    assert ":1:" in _error(tmp_path, "") and "empty" in _error(tmp_path, "")
    assert ":1:" in _error(tmp_path, "\n  \n")
    hierarchy = MIXED[:MIXED.index("MOTION")]
    message = _error(tmp_path, hierarchy)
    assert "missing MOTION" in message and f":{len(hierarchy.splitlines())}:" in message
    message = _error(tmp_path, MIXED[MIXED.index("MOTION"):])
    assert ":1:" in message and "HIERARCHY" in message
    message = _error(tmp_path, hierarchy + "MOTION\n")
    assert "Frames" in message
    with pytest.raises(DoodleError, match="cannot read"):
        read_bvh(tmp_path / "nope.bvh")


def test_extra_frames_are_ignored_but_blank_lines_allowed(tmp_path):
    text = MIXED.replace("Frames: 2", "Frames: 1").replace("Frame Time: 0.0333333\n", "Frame Time: 0.0333333\n\n")
    motion = read_bvh(_write(tmp_path, text))
    assert motion.frames == 1


# --------------------------------------------------------------------------- writing


def test_write_is_atomic_and_refuses_unfaithful_motion(tmp_path):
    motion = read_bvh(_write(tmp_path, MIXED), unit=1.0)
    out = tmp_path / "keep.bvh"
    out.write_text("old contents\n")
    bad = motion.rotations.copy()
    bad[1, 2] = np.nan
    with pytest.raises(DoodleError, match="non-finite"):
        write_bvh(out, replace(motion, rotations=bad))
    moved = motion.translations.copy()
    moved[1, 1] += 0.5  # Spine has no position channels
    with pytest.raises(DoodleError, match="Spine.*position channels"):
        write_bvh(out, replace(motion, translations=moved))
    assert out.read_text() == "old contents\n"
    assert sorted(os.listdir(tmp_path)) == ["clip.bvh", "keep.bvh"]  # no temporary files left
    write_bvh(out, motion)
    assert out.read_text() == format_bvh(motion)


def test_write_without_channel_layout_uses_defaults(tmp_path):
    motion = read_bvh(_write(tmp_path, MIXED), unit=1.0)
    sk = replace(motion.skeleton, channels=((),) * len(motion.skeleton))
    bare = replace(motion, skeleton=sk)
    write_bvh(tmp_path / "d.bvh", bare)
    again = read_bvh(tmp_path / "d.bvh", unit=1.0)
    assert again.skeleton.channels[0] == ("Xposition", "Yposition", "Zposition", "Zrotation", "Xrotation", "Yrotation")
    assert again.skeleton.channels[1] == ("Zrotation", "Xrotation", "Yrotation")
    assert again.skeleton.channels[3][:3] == ("Xposition", "Yposition", "Zposition")  # the Slider moves
    np.testing.assert_allclose(forward_kinematics(again)[0], forward_kinematics(motion)[0], atol=1e-5)


def test_write_skeleton_not_in_depth_first_order(tmp_path):
    """A parents-first skeleton that is not depth first ([root, A, B, A1, B1]) is written in
    the file's depth-first joint order, with each joint's values in its own columns."""
    motion = read_bvh(_write(tmp_path, MIXED), unit=1.0)  # Hips, Spine, Head, Slider, Foot
    perm = [0, 1, 3, 2, 4]  # Hips, Spine, Slider, Head, Foot
    sk = motion.skeleton
    inverse = np.argsort(perm)
    parents = np.array([-1 if sk.parents[j] < 0 else inverse[sk.parents[j]] for j in perm])
    shuffled_sk = replace(sk, names=tuple(sk.names[j] for j in perm), parents=parents,
                          offsets=sk.offsets[perm], channels=tuple(sk.channels[j] for j in perm),
                          end_sites={int(inverse[j]): v for j, v in sk.end_sites.items()})
    shuffled = replace(motion, skeleton=shuffled_sk, translations=motion.translations[:, perm],
                       rotations=motion.rotations[:, perm])
    write_bvh(tmp_path / "s.bvh", shuffled, unit=1.0)
    again = read_bvh(tmp_path / "s.bvh", unit=1.0)
    assert again.skeleton.names == sk.names
    np.testing.assert_allclose(forward_kinematics(again)[0], forward_kinematics(motion)[0], atol=1e-5)
    ends = end_site_positions(again)
    np.testing.assert_allclose(ends[4], end_site_positions(motion)[4], atol=1e-5)
