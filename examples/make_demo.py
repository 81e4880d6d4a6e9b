"""Regenerate examples/demo.doodle: the thesis's main example, performed by doodle.synth.

A figurine waits, side-steps to its left, turns right, walks forward, jumps forward,
walks on and stops (thesis Fig. 4.3 and 4.6). Run: python examples/make_demo.py
"""

from pathlib import Path

from doodle.fileformat import write_doodle
from doodle.synth import stroke, synth_doodle

STROKES = [
    stroke("T_STILL", 0.8),
    stroke("T_X", 1.2, 0.12),  # side walk left
    stroke("T_STILL", 0.3),
    stroke("R_N_Y", 0.7, 1.3),  # turn right
    stroke("T_STILL", 0.3),
    stroke("T_Z", 1.6, 0.18),  # walk forward
    stroke("T_Y_Z", 0.35, 0.07),  # jump: up and forward ...
    stroke("T_N_Y_Z", 0.35, 0.07),  # ... down and forward
    stroke("T_Z", 1.2, 0.12),  # walk on
    stroke("T_STILL", 0.8),
]

if __name__ == "__main__":
    doodle = synth_doodle({"c0": STROKES}, rate=90.0, seed=7, device="vive-controller")
    out = Path(__file__).with_name("demo.doodle")
    write_doodle(out, doodle, convention="openvr")
    print(f"wrote {out}")
