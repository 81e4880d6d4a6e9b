"""Offscreen rendering: milliseconds per 640×480 frame of the compiled demo scene
(pyrender, EGL, CPU rasteriser here), and the first frame, which also sets the scene up."""

import time
from pathlib import Path

from doodle.input.loader import load
from doodle.app.pipeline import compile_doodle

DEMO = Path(__file__).resolve().parents[1] / "examples" / "demo.doodle"


def main() -> None:
    from doodle.app import render
    from doodle.core.errors import DoodleError

    try:
        render.load_pyrender()
    except DoodleError as e:
        print(f"Rendering: skipped ({e})")
        return
    results = compile_doodle(load(DEMO))
    frames = 40
    start = time.perf_counter()
    first = None
    for k, _ in enumerate(render.render_frames(results, None, (640, 480), frames=frames)):
        if k == 0:
            first = time.perf_counter() - start
    total = time.perf_counter() - start
    print(f"Rendering {frames} frames at 640x480: {(total - first) / (frames - 1) * 1000:.1f} ms per frame "
          f"(first frame, with the scene set up: {first * 1000:.0f} ms)")


if __name__ == "__main__":
    main()
