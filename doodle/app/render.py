"""Offscreen 3D renders of a compiled doodle: frames, a key-frame sheet, a GIF or an MP4.

:func:`render_frames` draws the animations of :func:`doodle.app.pipeline.compile_doodle` with
pyrender through EGL (no display needed; Mesa's llvmpipe renders on the CPU):

* the ground — a checkered grid over the framed area (1 m squares) following the terrain's
  heights, or a :class:`retarget.terrain.Mesh` terrain's own triangles;
* each character as a stick figure — a cylinder per bone (parent to child, and to each End
  Site) and a sphere per joint, built once and posed per frame;
* each track's doodle (``projected``) as a thin tube on the ground, coloured by recognised
  action with the colours of ``retarget/preview.py``'s plan view (matplotlib's tab20 over
  the sorted action names), drawn unlit so those colours come out exactly;
* a light and one fixed camera framing every character's whole motion.

Writers (:func:`write_sheet`, :func:`write_gif`, :func:`write_mp4`) write to a temporary
file beside the output and rename it, so a failed render leaves an existing file untouched.

pyrender 0.1.45 needs ``PYOPENGL_PLATFORM=egl`` set before it is imported and still uses
``np.infty`` (gone in numpy 2); :func:`load_pyrender` sees to both. When pyrender or EGL is
missing, rendering raises :class:`doodle.core.errors.DoodleError` with one line saying what to
install.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from doodle.core.errors import DoodleError
from doodle.core.files import atomic_path

INSTALL = "pip install pyrender==0.1.45 imageio-ffmpeg; Debian/Ubuntu: apt-get install libegl1 libgl1-mesa-dri"

# matplotlib's tab20, indexed as retarget.preview.plan_view does (sorted action names).
TAB20 = ("#1f77b4", "#aec7e8", "#ff7f0e", "#ffbb78", "#2ca02c", "#98df8a", "#d62728", "#ff9896",
         "#9467bd", "#c5b0d5", "#8c564b", "#c49c94", "#e377c2", "#f7b6d2", "#7f7f7f", "#c7c7c7",
         "#bcbd22", "#dbdb8d", "#17becf", "#9edae5")
# Characters' bone colours in turn (linear RGB, lit); joints are drawn darker.
CHARACTER_COLOURS = ((0.95, 0.62, 0.30), (0.30, 0.62, 0.95), (0.45, 0.85, 0.35), (0.90, 0.40, 0.80))
SKY = (0.82, 0.87, 0.93)
GROUND = ((0.30, 0.32, 0.34), (0.42, 0.44, 0.46))  # checker squares, linear RGB
SHOW = ("ground", "curve", "characters")

BONE_RADIUS = 0.028  # metres
JOINT_RADIUS = 0.04
HEAD_RADIUS = 0.1
CURVE_RADIUS = 0.022
YFOV = np.radians(40.0)
ELEVATION = np.radians(32.0)  # camera above the horizon
AZIMUTH = np.radians(55.0)  # camera position from +z (the characters' front) towards +x (their left)


def load_pyrender():
    """pyrender, imported for offscreen EGL rendering (DoodleError when it cannot be)."""
    os.environ.setdefault("PYOPENGL_PLATFORM", "egl")
    if not hasattr(np, "infty"):
        np.infty = np.inf  # pyrender 0.1.45 still uses the alias numpy 2 removed
    try:
        import pyrender
    except Exception as e:  # ImportError, or OpenGL failing to find its platform library
        platform = os.environ["PYOPENGL_PLATFORM"]
        raise DoodleError(f"3D rendering needs pyrender and OpenGL through {platform} ({_first_line(e)}): "
                          f"{INSTALL}") from None
    return pyrender


def _first_line(e: BaseException) -> str:
    """An exception's message on one line (PyOpenGL raises with a tuple of strings)."""
    parts = [str(a) for a in e.args if isinstance(a, str) and a] if len(e.args) > 1 else [str(e)]
    text = ": ".join(parts).strip()
    return text.splitlines()[0] if text else type(e).__name__


def action_colours(results) -> dict[str, tuple[float, float, float]]:
    """RGB in [0, 1] per action, as the plan view colours them."""
    names = sorted({s.action for r in results for s in r.segments})
    return {name: tuple(int(TAB20[i % 20][k:k + 2], 16) / 255 for k in (1, 3, 5)) for i, name in enumerate(names)}


def frame_indices(results, fps: float | None = None, frames: int | None = None) -> np.ndarray:
    """The animation frames to draw: every frame; or resampled to ``fps`` (nearest frame);
    or ``frames`` of them spread evenly over the clip (first and last included)."""
    if not results:
        raise DoodleError("nothing to render: no animation")
    total = max(r.motion.frames for r in results)
    if frames is not None:
        if frames < 1:
            raise DoodleError(f"frames must be 1 or more, not {frames}")
        return np.linspace(0, total - 1, frames).round().astype(int)
    if fps is None:
        return np.arange(total)
    if not 0 < fps < float("inf"):
        raise DoodleError(f"fps must be a positive number, not {fps:g}")
    dt = results[0].motion.frame_time
    t = np.arange(0.0, (total - 1) * dt + 1e-9, 1.0 / fps)
    return np.minimum(np.round(t / dt).astype(int), total - 1)


def render_frames(results, terrain=None, size=(640, 480), fps=None, frames=None, progress=None, show=SHOW):
    """RGB uint8 frames (h, w, 3) of the animations, one per :func:`frame_indices`.

    ``terrain`` defaults to the one the results were compiled on (flat y = 0 if none).
    ``progress(i, n)`` is called after each frame; ``show`` picks what is drawn among
    ``"ground"``, ``"curve"`` and ``"characters"`` (the camera frames the same scene
    whatever is shown). The scene and the offscreen context are set up before this returns,
    so a missing pyrender or EGL raises here; the frames are rendered as they are taken.

    The camera and everything but the characters stand still, so that background is
    rendered once and each frame renders only the characters over it (by depth).
    """
    width, height = (int(v) for v in size)
    if width < 8 or height < 8:
        raise DoodleError(f"image size must be at least 8x8 pixels, not {width}x{height}")
    picks = frame_indices(results, fps, frames)
    pyrender = load_pyrender()
    import trimesh

    terrain = terrain if terrain is not None else next((r.terrain for r in results if r.terrain is not None), None)
    figures = [_Figure(r, CHARACTER_COLOURS[k % len(CHARACTER_COLOURS)], trimesh) for k, r in enumerate(results)]
    framed = np.concatenate([f.points() for f in figures] + [r.projected for r in results if r.projected is not None])
    aspect = width / height
    camera = camera_pose(framed, aspect)
    still = _scene(pyrender, camera, aspect, (*SKY, 1.0))
    if "ground" in show:
        still.add(_ground(np.concatenate([framed, _seen_ground(camera, aspect, framed)]), terrain, pyrender))
    if "curve" in show:
        for mesh in _curves(results, pyrender, trimesh):
            still.add(mesh)
    moving = _scene(pyrender, camera, aspect, (0.0, 0.0, 0.0, 0.0))
    try:
        renderer = pyrender.OffscreenRenderer(width, height)
    except Exception as e:
        platform = os.environ.get("PYOPENGL_PLATFORM", "egl")
        raise DoodleError(f"cannot open an offscreen OpenGL context through {platform} ({_first_line(e)}): "
                          f"{INSTALL}") from None
    return _frames(renderer, still, moving, figures if "characters" in show else [], picks, progress, pyrender)


def _scene(pyrender, camera: np.ndarray, aspect: float, background):
    """An empty scene with the camera and the lights."""
    scene = pyrender.Scene(bg_color=background, ambient_light=(0.30, 0.30, 0.32))
    scene.add(pyrender.PerspectiveCamera(yfov=YFOV, aspectRatio=aspect, znear=0.05, zfar=1000.0), pose=camera)
    scene.add(pyrender.DirectionalLight(color=np.ones(3), intensity=3.0), pose=_look(np.array([0.5, -1.0, -0.4])))
    scene.add(pyrender.DirectionalLight(color=np.ones(3), intensity=1.0), pose=_look(np.array([-0.6, -0.3, 0.8])))
    return scene


def _frames(renderer, still, moving, figures, picks, progress, pyrender):
    try:
        colour, depth = renderer.render(still)
        background = np.array(colour[..., :3], dtype=np.uint8)
        node = None
        for i, f in enumerate(picks):
            frame = background
            if figures:
                if node is not None:
                    moving.remove_node(node)
                node = moving.add(pyrender.Mesh([figure.primitive(int(f), pyrender) for figure in figures]))
                rgba, near = renderer.render(moving, flags=pyrender.RenderFlags.RGBA)
                frame = _over(rgba, near, background, depth)
            if progress:
                progress(i + 1, len(picks))
            yield np.array(frame, dtype=np.uint8)
    finally:
        renderer.delete()


def _over(rgba: np.ndarray, near: np.ndarray, background: np.ndarray, depth: np.ndarray) -> np.ndarray:
    """The characters' render (premultiplied by its coverage) over the background, where
    they are nearer than it (depth 0: nothing there)."""
    out = background.copy()
    rows, cols = np.nonzero((near > 0) & ((depth == 0) | (near < depth)))
    alpha = rgba[rows, cols, 3:4] / 255.0
    out[rows, cols] = np.clip(np.rint(rgba[rows, cols, :3] + (1.0 - alpha) * background[rows, cols]), 0, 255)
    return out


class _Figure:
    """One character: a cylinder per bone (parent → child, joint → End Site), a sphere per
    joint and one for the head, merged into one mesh per frame."""

    def __init__(self, result, colour, trimesh):
        from retarget.skeleton import end_site_positions, forward_kinematics

        sk = result.motion.skeleton
        world = forward_kinematics(result.motion)
        self.positions = world[0]  # (F, J, 3)
        self.ends = end_site_positions(result.motion, world)  # joint -> (F, 3)
        self.parents = np.array([int(sk.parents[j]) for j in range(1, len(sk))] + list(self.ends), dtype=int)
        self.children = list(range(1, len(sk))) + [("end", j) for j in self.ends]
        head = (result.roles or {}).get("head")
        self.head = int(head) if head is not None else None
        cylinder = trimesh.creation.cylinder(radius=BONE_RADIUS, height=1.0, sections=10)
        self.cylinder = cylinder.vertices[cylinder.faces].reshape(-1, 3)
        normals = np.repeat(cylinder.face_normals, 3, axis=0)  # caps flat, sides round:
        side = np.abs(normals[:, 2]) < 0.5
        normals[side] = self.cylinder[side] * (1.0, 1.0, 0.0) / BONE_RADIUS
        self.cylinder_normals = normals
        sphere = trimesh.creation.icosphere(subdivisions=2, radius=1.0)
        self.sphere = sphere.vertices[sphere.faces].reshape(-1, 3)
        self.colour = np.asarray(colour)

    def points(self) -> np.ndarray:
        """Every joint and End Site over the whole motion (what the camera must see)."""
        return np.concatenate([self.positions.reshape(-1, 3)] + list(self.ends.values()))

    def primitive(self, f: int, pyrender):
        """The posed figure at frame ``f`` (the last frame after its end)."""
        f = min(f, len(self.positions) - 1)
        joints = self.positions[f]
        a = joints[self.parents]
        b = np.array([self.ends[c[1]][f] if isinstance(c, tuple) else joints[c] for c in self.children])
        rot, length = _bone_frames(a, b)
        bones = np.einsum("bij,vj->bvi", rot, self.cylinder * (1.0, 1.0, 0.0)) \
            + np.einsum("bi,v->bvi", b - a, self.cylinder[:, 2]) + ((a + b) / 2)[:, None]
        bone_normals = np.einsum("bij,vj->bvi", rot, self.cylinder_normals)
        centres = [joints, ] + ([] if self.head is None else [self._head(f)[None]])
        radii = [JOINT_RADIUS] * len(joints) + ([] if self.head is None else [HEAD_RADIUS])
        centres = np.concatenate(centres)
        balls = self.sphere[None] * np.asarray(radii)[:, None, None] + centres[:, None]
        ball_normals = np.broadcast_to(self.sphere, balls.shape)
        colours = np.concatenate([np.tile(self.colour, (bones.shape[0] * bones.shape[1], 1)),
                                  np.tile(0.4 * self.colour, (len(joints) * len(self.sphere), 1)),
                                  np.tile(self.colour, ((self.head is not None) * len(self.sphere), 1))])
        material = pyrender.MetallicRoughnessMaterial(baseColorFactor=(1.0, 1.0, 1.0, 1.0), metallicFactor=0.0,
                                                      roughnessFactor=0.6)
        return pyrender.Primitive(positions=np.concatenate([bones.reshape(-1, 3), balls.reshape(-1, 3)]),
                                  normals=np.concatenate([bone_normals.reshape(-1, 3), ball_normals.reshape(-1, 3)]),
                                  color_0=colours, material=material)

    def _head(self, f: int) -> np.ndarray:
        """The middle of the head: between the head joint and its End Site."""
        base = self.positions[f, self.head]
        top = self.ends[self.head][f] if self.head in self.ends else base + (0.0, 0.2, 0.0)
        return (base + top) / 2


def _bone_frames(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per bone a → b, the rotation taking +z along it (Rodrigues) and its length."""
    d = b - a
    length = np.linalg.norm(d, axis=1)
    x, y, z = (d / np.maximum(length, 1e-9)[:, None]).T
    z = np.where(length > 1e-9, z, 1.0)
    k = 1.0 / np.maximum(1.0 + z, 1e-9)
    rot = np.empty((len(d), 3, 3))
    rot[:, 0] = np.column_stack([1 - x * x * k, -x * y * k, x])
    rot[:, 1] = np.column_stack([-x * y * k, 1 - y * y * k, y])
    rot[:, 2] = np.column_stack([-x, -y, z])
    rot[z < -1 + 1e-9] = np.diag([1.0, -1.0, -1.0])
    return rot, length


def _look(direction: np.ndarray, position=np.zeros(3)) -> np.ndarray:
    """A pose whose −z axis points along ``direction`` with +y as up as far as possible."""
    back = -direction / np.linalg.norm(direction)
    right = np.cross((0.0, 1.0, 0.0), back)
    if np.linalg.norm(right) < 1e-6:
        right = np.array([1.0, 0.0, 0.0])
    right /= np.linalg.norm(right)
    m = np.eye(4)
    m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = right, np.cross(back, right), back, position
    return m


def camera_pose(points: np.ndarray, aspect: float, yfov: float = YFOV) -> np.ndarray:
    """A fixed camera looking down at the points' box from the front-left, just far enough
    back for every point to fall inside the picture (with a small margin)."""
    lo, hi = points.min(axis=0), points.max(axis=0)
    centre = (lo + hi) / 2
    back = np.array([np.sin(AZIMUTH) * np.cos(ELEVATION), np.sin(ELEVATION), np.cos(AZIMUTH) * np.cos(ELEVATION)])
    pose = _look(-back)
    q = points - centre
    ty = 0.9 * np.tan(yfov / 2)
    tx = ty * aspect
    xc, yc, zc = q @ pose[:3, 0], q @ pose[:3, 1], q @ pose[:3, 2]
    dist = max(float(np.max(np.maximum(np.abs(xc) / tx, np.abs(yc) / ty) + zc)), 1.0)
    pose[:3, 3] = centre + dist * back
    return pose


def _seen_ground(pose: np.ndarray, aspect: float, framed: np.ndarray, yfov: float = YFOV,
                 far: float = 60.0) -> np.ndarray:
    """Where the picture's corner rays meet the lowest framed height (at most ``far``
    metres away): the ground must reach that far not to show its edge."""
    ty = np.tan(yfov / 2)
    y0 = float(framed[:, 1].min())
    origin = pose[:3, 3]
    out = []
    for sx, sy in ((-1, -1), (1, -1), (-1, 1), (1, 1)):
        ray = pose[:3, :3] @ np.array([sx * ty * aspect, sy * ty, -1.0])
        ray /= np.linalg.norm(ray)
        t = (y0 - origin[1]) / ray[1] if ray[1] < -1e-9 else far
        out.append(origin + min(t, far) * ray)
    return np.array(out)


def _ground(framed: np.ndarray, terrain, pyrender):
    """The ground under the framed points: a Mesh terrain's triangles, else a grid (1 m
    checker squares) at the terrain's heights, flat y = 0 without a terrain."""
    from retarget.terrain import Flat, Mesh

    if isinstance(terrain, Mesh):
        vertices, faces = np.asarray(terrain.vertices), np.asarray(terrain.faces)
    else:
        lo = np.floor(framed[:, [0, 2]].min(axis=0) - 1.0)
        hi = np.ceil(framed[:, [0, 2]].max(axis=0) + 1.0)
        # Flat: 1 m cells (the checker); else fine enough for the relief, at most 300 cells a side
        # (the ground is drawn once per clip, so triangles are cheap).
        step = 1.0 if terrain is None or isinstance(terrain, Flat) else \
            next(s for s in (0.05, 0.1, 0.2, 0.25, 0.5, 1.0, 2.0, 5.0, 10.0) if (hi - lo).max() / s <= 300)
        xs, zs = np.arange(lo[0], hi[0] + step / 2, step), np.arange(lo[1], hi[1] + step / 2, step)
        X, Z = np.meshgrid(xs, zs)
        xz = np.column_stack([X.ravel(), Z.ravel()])
        heights = np.zeros(len(xz)) if terrain is None else terrain.height(xz)
        vertices = np.column_stack([xz[:, 0], heights, xz[:, 1]])
        idx = np.arange(len(xz)).reshape(len(zs), len(xs))
        a, b, c, d = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, 1:].ravel()
        faces = np.concatenate([np.column_stack([a, b, c]), np.column_stack([c, b, d])])
    corners = vertices[faces]  # (T, 3, 3)
    centroids = corners.mean(axis=1)
    checker = (np.floor(centroids[:, 0] + 1e-6) + np.floor(centroids[:, 2] + 1e-6)).astype(int) % 2
    normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    normals *= np.sign(normals[:, 1:2] + 1e-12) / np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-12)
    material = pyrender.MetallicRoughnessMaterial(baseColorFactor=(1.0, 1.0, 1.0, 1.0), metallicFactor=0.0,
                                                  roughnessFactor=0.9)
    primitive = pyrender.Primitive(positions=corners.reshape(-1, 3), normals=np.repeat(normals, 3, axis=0),
                                   color_0=np.repeat(np.asarray(GROUND)[checker], 3, axis=0), material=material)
    return pyrender.Mesh([primitive])


def _curves(results, pyrender, trimesh) -> list:
    """Each track's projected doodle as tubes, one unlit mesh per action colour."""
    colours = action_colours(results)
    pieces: dict[str, list] = {}
    for r in results:
        if r.projected is None:
            continue
        points = np.asarray(r.projected, dtype=float)
        for s in r.segments:
            part = points[s.start:min(s.end + 1, len(points))]
            tube = _tube(part + (0.0, 1.5 * CURVE_RADIUS, 0.0), CURVE_RADIUS, trimesh)
            if tube is not None:
                pieces.setdefault(s.action, []).append(tube)
    meshes = []
    for action, tubes in pieces.items():
        # Unlit: black base, fully metallic (no diffuse, no specular) and emissive. pyrender
        # multiplies the emissive factor in twice, then applies gamma 1/2.2, so c^1.1 shows c.
        material = pyrender.MetallicRoughnessMaterial(
            baseColorFactor=(0.0, 0.0, 0.0, 1.0), metallicFactor=1.0, roughnessFactor=1.0,
            emissiveFactor=np.asarray(colours[action]) ** 1.1)
        meshes.append(pyrender.Mesh.from_trimesh(trimesh.util.concatenate(tubes), material=material, smooth=False))
    return meshes


def _tube(points: np.ndarray, radius: float, trimesh, sections: int = 6):
    """A tube of ``radius`` along a polyline (None when the polyline has no length)."""
    keep = np.concatenate([[True], np.linalg.norm(np.diff(points, axis=0), axis=1) > radius / 4])
    p = points[keep]
    if len(p) < 2:
        return None
    tangent = np.gradient(p, axis=0)
    tangent /= np.linalg.norm(tangent, axis=1, keepdims=True)
    side = np.cross(tangent, (0.0, 1.0, 0.0))
    flat = np.linalg.norm(side, axis=1) < 1e-6
    side[flat] = np.cross(tangent[flat], (1.0, 0.0, 0.0))
    side /= np.linalg.norm(side, axis=1, keepdims=True)
    up = np.cross(side, tangent)
    angle = 2 * np.pi * np.arange(sections) / sections
    ring = np.cos(angle)[None, :, None] * side[:, None] + np.sin(angle)[None, :, None] * up[:, None]
    vertices = (p[:, None] + radius * ring).reshape(-1, 3)
    i, k = np.meshgrid(np.arange(len(p) - 1), np.arange(sections), indexing="ij")
    a, b = i * sections + k, i * sections + (k + 1) % sections
    c, d = a + sections, b + sections
    faces = np.concatenate([np.stack([a, c, b], -1).reshape(-1, 3), np.stack([b, c, d], -1).reshape(-1, 3)])
    return trimesh.Trimesh(vertices, faces, process=False)


# --- writers -----------------------------------------------------------------------------


def write_sheet(frames, path, columns: int = 4, labels=None) -> Path:
    """A PNG grid of the frames (``columns`` across), each labelled with ``labels[i]`` if given."""
    from PIL import Image, ImageDraw, ImageFont

    path = Path(path)
    tiles = [np.asarray(f, dtype=np.uint8) for f in frames]
    if not tiles:
        raise DoodleError(f"{path}: no frames to put on the sheet")
    h, w = tiles[0].shape[:2]
    gap, columns = 4, max(1, min(columns, len(tiles)))
    rows = -(-len(tiles) // columns)
    sheet = Image.new("RGB", (columns * w + (columns + 1) * gap, rows * h + (rows + 1) * gap), (255, 255, 255))
    draw = ImageDraw.Draw(sheet)
    font = ImageFont.load_default(size=max(10, h // 28))
    for i, tile in enumerate(tiles):
        x, y = gap + (i % columns) * (w + gap), gap + (i // columns) * (h + gap)
        sheet.paste(Image.fromarray(tile), (x, y))
        if labels is not None:
            draw.text((x + 6, y + 4), str(labels[i]), fill=(20, 20, 20), font=font)
    with atomic_path(path) as tmp:
        sheet.save(tmp, format="PNG")
    return path


def write_gif(frames, path, fps: float = 15.0) -> Path:
    """An endlessly looping GIF (Pillow; GIF delays are whole hundredths of a second)."""
    from PIL import Image

    path = Path(path)
    with atomic_path(path) as tmp:
        images = [Image.fromarray(np.asarray(f, dtype=np.uint8)).quantize(256) for f in frames]
        if not images:
            raise DoodleError(f"{path}: no frames to write")
        images[0].save(tmp, format="GIF", save_all=True, append_images=images[1:], loop=0,
                       duration=max(20, int(round(100.0 / fps)) * 10), disposal=1)
    return path


def write_mp4(frames, path, fps: float = 30.0) -> Path:
    """An H.264 MP4 through imageio-ffmpeg (odd sizes are padded to even ones)."""
    try:
        import imageio_ffmpeg
    except ImportError:
        raise DoodleError("writing MP4 needs imageio-ffmpeg: pip install imageio-ffmpeg") from None
    path = Path(path)
    with atomic_path(path) as tmp:
        writer, count = None, 0
        try:
            for f in frames:
                f = np.asarray(f, dtype=np.uint8)
                f = np.pad(f, ((0, f.shape[0] % 2), (0, f.shape[1] % 2), (0, 0)), mode="edge")
                if writer is None:
                    writer = imageio_ffmpeg.write_frames(tmp, (f.shape[1], f.shape[0]), fps=fps, codec="libx264",
                                                         macro_block_size=1, ffmpeg_log_level="error")
                    writer.send(None)
                writer.send(np.ascontiguousarray(f))
                count += 1
        finally:
            if writer is not None:
                writer.close()
        if not count:
            raise DoodleError(f"{path}: no frames to write")
    return path
