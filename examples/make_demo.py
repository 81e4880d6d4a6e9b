"""Regenerate examples/demo.doodle: the thesis's main example, performed by doodle.synth.strokes.

Thesis Fig. 4.7: Idle, Side Walk, Idle, Walk, Idle, Jump, Idle, Walk, Idle, Stomp — a
figurine waits, side-steps to its left, walks forward, hops forward (up, up-and-forward,
down-and-forward, down), walks on, and stomps in place. Run: python examples/make_demo.py
"""

from pathlib import Path

from doodle.input.fileformat import write_doodle
from doodle.synth.strokes import stroke, synth_doodle

STROKES = [
    stroke("T_STILL", 0.8),  # Idle
    stroke("T_X", 1.2, 0.12),  # Side Walk (left)
    stroke("T_STILL", 0.5),  # Idle
    stroke("T_Z", 1.5, 0.18),  # Walk
    stroke("T_STILL", 0.5),  # Idle
    stroke("T_Y", 0.25, 0.05),  # Jump: take off ...
    stroke("T_Y_Z", 0.25, 0.06),  # ... rise forward ...
    stroke("T_N_Y_Z", 0.25, 0.06),  # ... fall forward ...
    stroke("T_N_Y", 0.25, 0.05),  # ... land
    stroke("T_STILL", 0.5),  # Idle
    stroke("T_Z", 1.2, 0.14),  # Walk
    stroke("T_STILL", 0.5),  # Idle
    stroke("T_Y", 0.3, 0.06),  # Stomp: lift ...
    stroke("T_N_Y", 0.25, 0.06),  # ... and stamp
    stroke("T_STILL", 0.8),  # Idle
]

FIG_4_7 = ["Idle", "Side Walk Left", "Idle", "Walk", "Idle", "Jump", "Idle", "Walk", "Idle", "Stomp", "Idle"]

if __name__ == "__main__":
    doodle = synth_doodle({"c0": STROKES}, rate=90.0, seed=7, device="vive-controller")
    out = Path(__file__).with_name("demo.doodle")
    write_doodle(out, doodle, convention="openvr")
    print(f"wrote {out}")
