"""Terrain projection speed (retarget.terrain), all figures measured in the same run.

100,000 random points over the Jacksboro sample terrain (20 m across, 344 × 403 nodes,
heights 0–3 m; points from 2 m below to 6 m above) are projected along gravity onto

(a) the height field itself (bilinear lookup);
(b) its triangle mesh (``HeightField.to_mesh``, 2 × 343 × 402 = 275,772 triangles),
    Möller–Trumbore ray casting with the uniform xz grid acceleration (grid build timed
    separately);
(c) the same mesh by brute force — every ray against every triangle — on a subsample of
    ``BRUTE_POINTS`` points, reported as points per second (i.e. scaled per point).

Best of ``RUNS`` runs with ``time.perf_counter``. The mesh answers are checked against
brute force on the subsample and against the height field (they differ inside cells by at
most a quarter of the cell's twist, see ``HeightField.to_mesh``).
"""

from __future__ import annotations

import time

import numpy as np

from retarget.terrain import sample_elevation

N_POINTS = 100_000
BRUTE_POINTS = 300
RUNS = 3


def best_of(fn, runs: int = RUNS) -> tuple[float, object]:
    best, out = float("inf"), None
    for _ in range(runs):
        start = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - start)
    return best, out


def main(n_points: int = N_POINTS, brute_points: int = BRUTE_POINTS) -> int:
    hf = sample_elevation("jacksboro", 20.0)
    x0, x1, z0, z1 = hf.extent
    rng = np.random.default_rng(0)
    pts = np.column_stack(
        [rng.uniform(x0, x1, n_points), rng.uniform(-2.0, 6.0, n_points), rng.uniform(z0, z1, n_points)]
    )
    start = time.perf_counter()
    mesh = hf.to_mesh()
    t_to_mesh = time.perf_counter() - start
    start = time.perf_counter()
    grid = mesh.grid()
    t_grid = time.perf_counter() - start

    t_hf, out_hf = best_of(lambda: hf.project(pts))
    t_mesh, out_mesh = best_of(lambda: mesh.project(pts))
    sub = pts[:brute_points]
    t_brute, out_brute = best_of(lambda: mesh.project(sub, accelerated=False), runs=1)

    rows, cols = hf.shape
    print(f"Terrain projection — {n_points:,} points onto the Jacksboro sample ({rows}×{cols} nodes, 20 m)")
    print(f"  mesh: {len(mesh.faces):,} triangles (to_mesh {t_to_mesh * 1e3:.0f} ms); "
          f"xz grid {grid.nx}×{grid.nz} cells, {len(grid.cell_tris) / (grid.nx * grid.nz):.1f} "
          f"triangles per cell, built in {t_grid * 1e3:.0f} ms")
    print(f"  (a) height field, bilinear           {n_points / t_hf:14,.0f} points/s  ({t_hf * 1e3:8.1f} ms)")
    print(f"  (b) mesh, ray cast + grid            {n_points / t_mesh:14,.0f} points/s  ({t_mesh * 1e3:8.1f} ms)")
    print(f"  (c) mesh, ray cast brute force       {brute_points / t_brute:14,.0f} points/s  "
          f"({t_brute * 1e3:8.1f} ms for {brute_points} points)")
    print(f"  grid speed-up over brute force: {(n_points / t_mesh) / (brute_points / t_brute):,.0f}×")
    agree = np.max(np.abs(out_mesh[:brute_points] - out_brute))
    gap = np.max(np.abs(out_mesh[:, 1] - out_hf[:, 1]))
    print(f"  check: grid vs brute force max |Δ| = {agree:.2e} m; mesh vs bilinear max |Δ| = {gap:.3f} m")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
