"""Offscreen 3D rendering (doodle.app.render, doodle render): frames, sheet, GIF, MP4.

Rendering tests skip, with the reason, where pyrender or an EGL context cannot be had; the
rest (colours, geometry, errors) run everywhere.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

from doodle.app import render
from doodle.core.errors import DoodleError

DEMO = Path(__file__).resolve().parents[1] / "examples" / "demo.doodle"
SMALL = (160, 120)


@pytest.fixture(scope="module")
def results():
    from doodle.input.loader import load
    from doodle.app.pipeline import compile_doodle

    return compile_doodle(load(DEMO))


@pytest.fixture(scope="module")
def gl(results):
    """Skip rendering tests where pyrender/EGL is missing."""
    try:
        list(render.render_frames(results, size=(16, 16), frames=1))
    except DoodleError as e:
        pytest.skip(f"no offscreen rendering here: {e}")


def _frame(results, show=render.SHOW, size=SMALL, terrain=None):
    """The first frame."""
    return next(render.render_frames(results, terrain, size=size, frames=1, show=show))


def _near(image: np.ndarray, colour, tolerance: int = 6) -> int:
    """Pixels within ``tolerance`` (per channel, 0–255) of an RGB colour in [0, 1]."""
    target = np.round(255 * np.asarray(colour))
    return int(np.all(np.abs(image.astype(int) - target) <= tolerance, axis=-1).sum())


def _gif_frames(path) -> int:
    from PIL import Image

    with Image.open(path) as im:
        return im.n_frames


# --- without a GL context ------------------------------------------------------------------


def test_action_colours_are_the_plan_views(results):
    from matplotlib import colormaps

    names = sorted({s.action for r in results for s in r.segments})
    tab20 = colormaps["tab20"]
    assert sorted(render.action_colours(results)) == names
    for name, colour in render.action_colours(results).items():
        assert np.allclose(colour, tab20(names.index(name) % 20)[:3], atol=1e-6)


def test_bone_frames_take_z_along_each_bone():
    rng = np.random.default_rng(3)
    a = rng.normal(size=(50, 3))
    d = np.concatenate([rng.normal(size=(46, 3)), [[0, 0, 1], [0, 0, -2], [1e-3, 0, -1], [0, 3, 0]]])
    rot, length = render._bone_frames(a, a + d)
    assert np.allclose(length, np.linalg.norm(d, axis=1))
    assert np.allclose(rot[:, :, 2], d / length[:, None], atol=1e-9)
    assert np.allclose(rot @ rot.transpose(0, 2, 1), np.eye(3), atol=1e-9)
    assert np.allclose(np.linalg.det(rot), 1.0)


def test_frame_indices(results):
    total = results[0].motion.frames
    assert list(render.frame_indices(results)) == list(range(total))
    picks = render.frame_indices(results, frames=8)
    assert len(picks) == 8 and picks[0] == 0 and picks[-1] == total - 1
    assert len(render.frame_indices(results, fps=15)) == (total + 1) // 2
    with pytest.raises(DoodleError):
        render.frame_indices(results, frames=0)


def test_camera_sees_every_point():
    rng = np.random.default_rng(0)
    points = rng.uniform((-3, 0, -1), (4, 2, 6), size=(500, 3))
    pose = render.camera_pose(points, 4 / 3)
    local = (points - pose[:3, 3]) @ pose[:3, :3]  # camera frame: looks along -z
    depth = -local[:, 2]
    assert np.all(depth > 0)
    assert np.all(np.abs(local[:, 1] / depth) <= np.tan(render.YFOV / 2) + 1e-9)
    assert np.all(np.abs(local[:, 0] / depth) <= 4 / 3 * np.tan(render.YFOV / 2) + 1e-9)


def test_missing_pyrender_is_one_clear_line(monkeypatch):
    monkeypatch.setitem(sys.modules, "pyrender", None)  # import pyrender now raises ImportError
    with pytest.raises(DoodleError) as e:
        render.load_pyrender()
    assert "pip install pyrender" in str(e.value) and "\n" not in str(e.value)


def _cli(argv):
    from doodle.app.cli.main import build_parser

    parser = build_parser(["render"])
    args = parser.parse_args(["render", *argv])
    return args.run(args)


def test_cli_bad_extension(tmp_path):
    out = tmp_path / "clip.avi"
    with pytest.raises(DoodleError, match=r"clip\.avi: unknown output type '\.avi'.*\.png.*\.gif.*\.mp4"):
        _cli([str(DEMO), "-o", str(out)])
    assert not out.exists()


def test_cli_bad_size(tmp_path):
    with pytest.raises(DoodleError, match="--size"):
        _cli([str(DEMO), "-o", str(tmp_path / "a.png"), "--size", "640"])


def test_sheet_size_and_atomic_writes(tmp_path):
    tiles = [np.full((48, 64, 3), 40 * k, dtype=np.uint8) for k in range(6)]
    sheet = render.write_sheet(tiles, tmp_path / "sheet.png", columns=4, labels=[f"{k}" for k in range(6)])
    from PIL import Image

    with Image.open(sheet) as im:
        assert im.size == (4 * 64 + 5 * 4, 2 * 48 + 3 * 4)

    def failing():
        yield tiles[0]
        yield tiles[1]
        raise RuntimeError("render failed")

    for name, write in (("old.png", render.write_sheet), ("old.gif", render.write_gif), ("old.mp4", render.write_mp4)):
        out = tmp_path / name
        out.write_bytes(b"keep me")
        with pytest.raises(RuntimeError, match="render failed"):
            write(failing(), out)
        assert out.read_bytes() == b"keep me"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["old.gif", "old.mp4", "old.png", "sheet.png"]


# --- rendering -----------------------------------------------------------------------------


def test_frames_are_not_blank(results, gl):
    frames = list(render.render_frames(results, size=SMALL, frames=3))
    assert len(frames) == 3
    for f in frames:
        assert f.shape == (SMALL[1], SMALL[0], 3) and f.dtype == np.uint8
        assert f.reshape(-1, 3).std(axis=0).max() > 10
    assert np.any(frames[0] != frames[-1])  # the character moved


def test_characters_are_visible(results, gl):
    with_them = _frame(results)
    without = _frame(results, show=("ground", "curve"))
    changed = np.any(np.abs(with_them.astype(int) - without.astype(int)) > 12, axis=-1)
    assert changed.sum() > 0.004 * changed.size
    drawn = with_them[changed].astype(int)  # the character's warm colour, not the grey ground
    assert (drawn[:, 0] - drawn[:, 2]).mean() > 25


def test_doodle_curve_in_action_colours(results, gl):
    colours = render.action_colours(results)
    moving = {s.action for r in results for s in r.segments
              if np.linalg.norm(np.diff(r.projected[s.start:s.end + 1], axis=0), axis=1).sum() > 0.5}
    assert moving  # the demo walks, side-walks and jumps
    size = (320, 240)
    shown = _frame(results, size=size)
    hidden = _frame(results, show=("ground", "characters"), size=size)
    for action in moving:
        assert _near(shown, colours[action]) >= 15, action
        assert _near(hidden, colours[action]) <= 2, action


def test_heightfield_ground_differs_from_flat(results, gl):
    from retarget.terrain import sample_elevation

    flat = _frame(results, show=("ground",), size=(80, 60))
    hills = _frame(results, show=("ground",), size=(80, 60), terrain=sample_elevation("jacksboro", 20.0))
    assert np.abs(flat.astype(int) - hills.astype(int)).mean() > 5


def test_mp4_and_gif_frame_counts(results, gl, tmp_path):
    import imageio.v2 as imageio

    mp4 = render.write_mp4(render.render_frames(results, size=(95, 71), frames=5), tmp_path / "clip.mp4", fps=10)
    reader = imageio.get_reader(mp4)
    assert reader.count_frames() == 5
    assert reader.get_meta_data()["size"] == (96, 72)  # odd sizes padded for H.264
    reader.close()
    gif = render.write_gif(render.render_frames(results, size=(64, 48), frames=4), tmp_path / "clip.gif", fps=10)
    assert _gif_frames(gif) == 4


def test_cli_renders_a_sheet_and_a_gif(results, gl, tmp_path, capsys):
    from PIL import Image

    sheet = tmp_path / "out" / "sheet.png"
    assert _cli([str(DEMO), "-o", str(sheet), "--size", "64x48", "--frames", "6"]) == 0
    with Image.open(sheet) as im:
        assert im.size == (4 * 64 + 5 * 4, 2 * 48 + 3 * 4)
    gif = tmp_path / "clip.gif"
    assert _cli([str(DEMO), "-o", str(gif), "--size", "48x36", "--fps", "5"]) == 0
    from doodle.input.loader import load

    assert _gif_frames(gif) == int(np.floor(load(DEMO).t[-1] * 5)) + 1  # every frame compiled at 5 fps
    assert "GIF of" in capsys.readouterr().out
