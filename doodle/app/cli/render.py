"""``doodle render FILE -o OUT.png|gif|mp4``: compile a doodle as ``doodle compile`` does and
render the animation offscreen in 3D (pyrender through EGL; see :mod:`doodle.app.render`).

``.png`` gives a key-frame sheet (8 frames spread over the clip unless ``--frames``),
``.gif`` and ``.mp4`` the animation (every frame at ``--fps``; with ``--frames N``, N frames
spread over the clip, played so the clip keeps its length).
"""

from __future__ import annotations

import time
from pathlib import Path

from doodle.core.errors import DoodleError
from doodle.app.cli.options import input_options

KINDS = {".png": "key-frame sheet", ".gif": "GIF", ".mp4": "MP4"}
SHEET_FRAMES = 8
SHEET_COLUMNS = 4


def add_arguments(p) -> None:
    """The arguments of ``doodle render``."""
    p.add_argument("file", metavar="FILE", help="a doodle file (.doodle, or .csv with --convention)")
    p.add_argument("-o", "--output", required=True, metavar="OUT.png|gif|mp4")
    p.add_argument("--overwrite", action="store_true", help="replace OUT if it exists")
    p.add_argument("--library", metavar="DIR", help="a user library (folder with library.toml)")
    p.add_argument("--terrain", metavar="SPEC", help="flat[:H], jacksboro[:SIZE], s1045[:SIZE], "
                   "heightfield:FILE.npz[:SPACING] or mesh:FILE.obj|ply|glb (default flat)")
    p.add_argument("--fps", type=float, default=30.0, help="animation and video frame rate (default 30)")
    p.add_argument("--size", default="640x480", metavar="WxH", help="pixels per frame (default 640x480)")
    p.add_argument("--frames", type=int, metavar="N",
                   help=f"N frames spread over the clip (default: {SHEET_FRAMES} on a sheet, every frame in a video)")
    input_options(p)
    p.set_defaults(run=cmd_render)


def parse_size(text: str) -> tuple[int, int]:
    """``"640x480"`` → ``(640, 480)``."""
    w, sep, h = str(text).lower().partition("x")
    try:
        size = (int(w), int(h))
    except ValueError:
        size = None
    if not sep or size is None or not (8 <= size[0] <= 8192 and 8 <= size[1] <= 8192):
        raise DoodleError(f"--size: expected WIDTHxHEIGHT in pixels (8 to 8192), like 640x480, not {text!r}")
    return size


def _label(results, frame: int, fps: float) -> str:
    """Time and the action each track performs at an output frame."""
    doing = []
    for r in results:
        action = next((s.action for s, (a, b) in zip(r.segments, r.frame_ranges or []) if a <= frame <= b), "-")
        doing.append(action if len(results) == 1 else f"{r.track} {action}")
    return f"{frame / fps:.2f} s  " + ", ".join(doing)


def cmd_render(args) -> int:
    from doodle.app import render
    from doodle.app.cli.options import progress_bar
    from doodle.core.files import output_file

    out = Path(args.output)
    suffix = out.suffix.lower()
    if suffix not in KINDS:
        raise DoodleError(f"{out}: unknown output type {out.suffix or '(none)'!r}; "
                          "use .png (key-frame sheet), .gif or .mp4")
    size = parse_size(args.size)
    if not 0 < args.fps < float("inf"):
        raise DoodleError(f"--fps must be a positive number, not {args.fps:g}")
    if args.frames is not None and args.frames < 1:
        raise DoodleError(f"--frames must be 1 or more, not {args.frames}")
    output_file(out, args.overwrite)
    render.load_pyrender()  # no pyrender or EGL: say so before compiling

    from doodle.app.cli.options import load_input
    from doodle.app.pipeline import compile_doodle
    from laban.models import load as load_effort_model
    from retarget.terrain import parse_terrain

    terrain = parse_terrain(args.terrain) if args.terrain else None
    doodle = load_input(args.file, args, None)
    results = compile_doodle(doodle, args.library, fps=args.fps, terrain=terrain, effort_model=load_effort_model(None))
    count = args.frames if args.frames is not None else (SHEET_FRAMES if suffix == ".png" else None)
    picks = render.frame_indices(results, frames=count)
    frames = render.render_frames(results, terrain, size, frames=count, progress=progress_bar("rendering"))
    start = time.perf_counter()
    if suffix == ".png":
        labels = [_label(results, int(f), args.fps) for f in picks]
        render.write_sheet(frames, out, columns=SHEET_COLUMNS, labels=labels)
    else:
        # N frames spread over the clip play at the rate that keeps the clip's length.
        span = picks[-1] - picks[0]
        fps = args.fps * (len(picks) - 1) / span if count is not None and span > 0 else args.fps
        (render.write_gif if suffix == ".gif" else render.write_mp4)(frames, out, fps=fps)
    seconds = time.perf_counter() - start
    print(f"{out}: {KINDS[suffix]} of {len(picks)} frames at {size[0]}x{size[1]} "
          f"({1000 * seconds / len(picks):.0f} ms per frame)")
    return 0


def can_preview() -> bool:
    """Whether `doodle compile --preview` can draw its 3D sheet: False, with a warning, where
    pyrender or EGL is missing — the other previews still come."""
    import warnings

    from doodle.app import render

    try:
        render.load_pyrender()
    except DoodleError as e:
        warnings.warn(f"no 3D preview: {e}")
        return False
    return True


def preview_sheet(results, terrain, path, fps: float, size=(480, 360)) -> Path:
    """The key-frame sheet `doodle compile --preview` puts beside the BVH (see :func:`can_preview`)."""
    from doodle.app import render

    picks = render.frame_indices(results, frames=SHEET_FRAMES)
    frames = render.render_frames(results, terrain, size, frames=SHEET_FRAMES)
    render.write_sheet(frames, Path(path), columns=SHEET_COLUMNS, labels=[_label(results, int(f), fps) for f in picks])
    return Path(path)
