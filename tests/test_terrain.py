"""Terrains (retarget.terrain): flat ground, height fields, meshes and their specs."""

from __future__ import annotations

import numpy as np
import pytest

from doodle.core.errors import DoodleError
from retarget.terrain import (
    SAMPLE_RELIEF_RATIO,
    Flat,
    HeightField,
    Mesh,
    moller_trumbore,
    parse_terrain,
    sample_elevation,
)

# ---------------------------------------------------------------------------- flat


def test_flat_project_lifts_and_lowers():
    ground = Flat(0.3)
    pts = np.array([[1.0, 2.0, -3.0], [0.5, -1.0, 4.0], [0.0, 0.3, 0.0]])
    out = ground.project(pts)
    np.testing.assert_array_equal(out[:, [0, 2]], pts[:, [0, 2]])
    np.testing.assert_array_equal(out[:, 1], 0.3)
    np.testing.assert_array_equal(ground.height(pts[:, [0, 2]]), 0.3)
    assert Flat().project([[1.0, 5.0, 2.0]])[0, 1] == 0.0


# ---------------------------------------------------------------------------- height field

GRID = np.array([[0.0, 1.0, 2.0], [2.0, 5.0, 3.0]])  # rows along z, columns along x


def test_heightfield_bilinear_at_known_points():
    hf = HeightField.from_array(GRID, spacing=2.0, origin=(10.0, -4.0))
    xz = np.array(
        [
            [10.0, -4.0],  # node (0, 0)
            [12.0, -2.0],  # node (1, 1)
            [11.0, -4.0],  # middle of the first x edge
            [11.0, -3.0],  # centre of the first cell: mean of 0, 1, 2, 5
            [10.5, -3.5],  # u = v = 0.25
            [13.0, -2.0],  # between 5 and 3
        ]
    )
    expected = [0.0, 5.0, 0.5, 2.0, 0.75**2 * 0 + 0.25 * 0.75 * 1 + 0.75 * 0.25 * 2 + 0.0625 * 5, 4.0]
    np.testing.assert_allclose(hf.height(xz), expected)


def test_heightfield_holds_edges_outside():
    hf = HeightField.from_array(GRID, spacing=1.0)
    xz = np.array([[-5.0, 0.0], [-5.0, 9.0], [9.0, -9.0], [9.0, 9.0], [0.5, -3.0], [0.5, 7.0]])
    np.testing.assert_allclose(hf.height(xz), [0.0, 2.0, 2.0, 3.0, 0.5, 3.5])


def test_heightfield_from_array_round_trip():
    rng = np.random.default_rng(1)
    h = rng.normal(size=(5, 7))
    hf = HeightField.from_array(h, spacing=0.25, origin=(-1.0, 2.0))
    j, i = np.meshgrid(np.arange(7), np.arange(5))
    xz = np.column_stack([-1.0 + 0.25 * j.ravel(), 2.0 + 0.25 * i.ravel()])
    np.testing.assert_allclose(hf.height(xz).reshape(5, 7), h, atol=1e-12)
    np.testing.assert_array_equal(hf.heights, h)
    assert hf.spacing == 0.25 and hf.origin == (-1.0, 2.0)
    assert hf.extent == (-1.0, 0.5, 2.0, 3.0)
    h[0, 0] = 99.0  # the field keeps its own copy
    assert hf.heights[0, 0] != 99.0


def test_heightfield_project_above_and_below():
    hf = HeightField.from_array(GRID)
    pts = np.array([[0.5, 10.0, 0.5], [0.5, -10.0, 0.5], [1.5, 2.0, 1.0]])
    out = hf.project(pts)
    np.testing.assert_allclose(out[:, 1], [2.0, 2.0, 4.0])
    np.testing.assert_array_equal(out[:, [0, 2]], pts[:, [0, 2]])


def test_heightfield_keeps_leading_shape():
    hf = HeightField.from_array(GRID)
    assert hf.project(np.zeros((4, 5, 3))).shape == (4, 5, 3)
    assert hf.height(np.zeros((4, 5, 2))).shape == (4, 5)


def test_heightfield_projects_100k_points():
    hf = sample_elevation()
    rng = np.random.default_rng(0)
    pts = rng.uniform(-12, 12, size=(100_000, 3))
    out = hf.project(pts)
    assert out.shape == pts.shape and np.all(np.isfinite(out))


# ---------------------------------------------------------------------------- mesh


def square_mesh(y=0.0):
    vertices = np.array([[0, y, 0], [1, y, 0], [1, y, 1], [0, y, 1]], dtype=float)
    faces = np.array([[0, 3, 1], [1, 3, 2]])
    return Mesh(vertices, faces)


def test_moller_trumbore_single_triangle():
    v0 = np.zeros(3)
    e1 = np.array([1.0, 0, 0])
    e2 = np.array([0, 0, 1.0])
    t, hit = moller_trumbore(np.array([[0.2, 3.0, 0.2], [0.8, 3.0, 0.8]]), np.array([0, -1.0, 0]), v0, e1, e2)
    np.testing.assert_allclose(t[0], 3.0)
    assert hit.tolist() == [True, False]


def test_mesh_two_triangle_square():
    mesh = square_mesh(y=0.5)
    pts = np.array([[0.25, 2.0, 0.75], [0.9, -3.0, 0.1], [0.5, 1.0, 0.5], [0.0, 1.0, 0.0], [1.0, 0.0, 1.0]])
    out = mesh.project(pts)
    np.testing.assert_allclose(out[:, 1], 0.5)
    np.testing.assert_array_equal(out[:, [0, 2]], pts[:, [0, 2]])
    np.testing.assert_allclose(mesh.height(pts[:, [0, 2]]), 0.5)


def test_mesh_tilted_plane_matches_analytic_height():
    # y = 0.3 x - 0.2 z + 1 over [-2, 2]², as a 3×3-node grid of triangles.
    n = 3
    xs = np.linspace(-2, 2, n)
    X, Z = np.meshgrid(xs, xs)
    Y = 0.3 * X - 0.2 * Z + 1
    mesh = HeightField.from_array(Y, spacing=2.0, origin=(-2.0, -2.0)).to_mesh()
    rng = np.random.default_rng(3)
    pts = np.column_stack([rng.uniform(-2, 2, 500), rng.uniform(-5, 5, 500), rng.uniform(-2, 2, 500)])
    analytic = 0.3 * pts[:, 0] - 0.2 * pts[:, 2] + 1
    np.testing.assert_allclose(mesh.project(pts)[:, 1], analytic, atol=1e-9)
    np.testing.assert_allclose(mesh.project(pts, accelerated=False)[:, 1], analytic, atol=1e-9)
    np.testing.assert_allclose(mesh.height(pts[:, [0, 2]]), analytic, atol=1e-9)


def test_mesh_misses_take_nearest_vertex_height():
    vertices = np.array([[0, 1.0, 0], [1, 2.0, 0], [0, 3.0, 1]])
    mesh = Mesh(vertices, np.array([[0, 2, 1]]))
    out = mesh.project(np.array([[5.0, 0.0, -0.1], [-3.0, 9.0, 2.0]]))
    np.testing.assert_allclose(out, [[5.0, 2.0, -0.1], [-3.0, 3.0, 2.0]])


def test_mesh_layers_closest_below_else_above():
    # two horizontal squares at y = 0 and y = 2
    a, b = square_mesh(0.0), square_mesh(2.0)
    mesh = Mesh(np.vstack([a.vertices, b.vertices]), np.vstack([a.faces, b.faces + 4]))
    pts = np.array([[0.5, 3.0, 0.5], [0.5, 1.0, 0.5], [0.5, -1.0, 0.5]])
    np.testing.assert_allclose(mesh.project(pts)[:, 1], [2.0, 0.0, 0.0])
    np.testing.assert_allclose(mesh.height([[0.5, 0.5]]), [2.0])


def grid_points(hf, rng, n):
    x0, x1, z0, z1 = hf.extent
    return np.column_stack([rng.uniform(x0, x1, n), rng.uniform(z0, z1, n)])


def test_heightfield_mesh_equals_grid_at_vertices_and_edges():
    rng = np.random.default_rng(7)
    h = rng.uniform(-1, 1, size=(6, 8))
    hf = HeightField.from_array(h, spacing=0.5, origin=(-2.0, 1.0))
    mesh = hf.to_mesh()
    assert len(mesh.faces) == 2 * 5 * 7
    # every grid node
    j, i = np.meshgrid(np.arange(8), np.arange(6))
    nodes = np.column_stack([-2.0 + 0.5 * j.ravel(), 1.0 + 0.5 * i.ravel()])
    np.testing.assert_allclose(mesh.height(nodes), h.ravel(), atol=1e-12)
    # along cell edges (x lines and z lines), both linear there
    s = rng.uniform(0, 1, 200)
    along_x = np.column_stack([-2.0 + 0.5 * (s * 7), 1.0 + 0.5 * rng.integers(0, 6, 200)])
    along_z = np.column_stack([-2.0 + 0.5 * rng.integers(0, 8, 200), 1.0 + 0.5 * (s * 5)])
    for xz in (along_x, along_z):
        np.testing.assert_allclose(mesh.height(xz), hf.height(xz), atol=1e-12)


def test_heightfield_mesh_close_to_bilinear_within_cell_twist():
    rng = np.random.default_rng(8)
    h = rng.uniform(-1, 1, size=(6, 8))
    hf = HeightField.from_array(h, spacing=0.5, origin=(-2.0, 1.0))
    mesh = hf.to_mesh()
    xz = grid_points(hf, rng, 2000)
    fx = (xz[:, 0] + 2.0) / 0.5
    fz = (xz[:, 1] - 1.0) / 0.5
    j = np.minimum(fx.astype(int), 6)
    i = np.minimum(fz.astype(int), 4)
    twist = h[i, j] - h[i, j + 1] - h[i + 1, j] + h[i + 1, j + 1]
    u, v = fx - j, fz - i
    diff = hf.height(xz) - mesh.height(xz)
    assert np.all(np.abs(diff) <= np.abs(twist) / 4 + 1e-12)
    # and exactly the analytic difference of bilinear vs the two planes
    expected = np.where(u + v <= 1, u * v, (1 - u) * (1 - v)) * twist
    np.testing.assert_allclose(diff, expected, atol=1e-12)
    assert np.max(np.abs(diff)) > 1e-3  # the two interpolations really differ inside cells


def random_mesh(rng, n_tri=300):
    """A soup of random, partly overlapping, tilted triangles (with layers and holes)."""
    centres = rng.uniform(-5, 5, size=(n_tri, 1, 3)) * [1, 0.4, 1]
    return Mesh((centres + rng.normal(scale=0.8, size=(n_tri, 3, 3))).reshape(-1, 3), np.arange(3 * n_tri).reshape(-1, 3))


def test_grid_acceleration_matches_brute_force():
    rng = np.random.default_rng(11)
    mesh = random_mesh(rng)
    pts = rng.uniform(-6.5, 6.5, size=(3000, 3))
    fast = mesh.project(pts)
    slow = mesh.project(pts, accelerated=False)
    np.testing.assert_allclose(fast, slow, atol=1e-12)
    np.testing.assert_allclose(mesh.height(pts[:, [0, 2]]), mesh.height(pts[:, [0, 2]], accelerated=False), atol=1e-12)
    # the soup has both hits and misses, and hits above and below
    assert np.any(fast[:, 1] > pts[:, 1]) and np.any(fast[:, 1] < pts[:, 1])
    grid = mesh.grid()
    assert grid.nx * grid.nz > 1


def test_grid_acceleration_on_heightfield_mesh_matches_brute_force():
    rng = np.random.default_rng(12)
    hf = HeightField.from_array(rng.normal(size=(20, 30)), spacing=0.1, origin=(0.0, 0.0))
    mesh = hf.to_mesh()
    xz = grid_points(hf, rng, 1000)
    pts = np.column_stack([xz[:, 0], rng.uniform(-5, 5, 1000), xz[:, 1]])
    np.testing.assert_allclose(mesh.project(pts), mesh.project(pts, accelerated=False), atol=1e-12)


def test_mesh_obj_loads_via_spec(tmp_path):
    path = tmp_path / "ground.obj"
    path.write_text(
        "# a 2 m square at y = 0.25 and a raised corner\n"
        "v -1 0.25 -1\nv 1 0.25 -1\nv 1 0.25 1\nv -1 0.25 1\n"
        "f 1 4 2\nf 2 4 3\n"
    )
    ground = parse_terrain(f"mesh:{path}")
    assert isinstance(ground, Mesh) and len(ground.faces) == 2
    np.testing.assert_allclose(ground.project([[0.3, 5.0, -0.4], [0.0, -2.0, 0.9]])[:, 1], 0.25)


def test_heightfield_npz_spec(tmp_path):
    path = tmp_path / "hf.npz"
    np.savez(path, heights=GRID, spacing=np.array(2.0), origin=np.array([1.0, 1.0]))
    hf = parse_terrain(f"heightfield:{path}")
    assert hf.spacing == 2.0 and hf.origin == (1.0, 1.0)
    np.testing.assert_array_equal(hf.heights, GRID)
    assert parse_terrain(f"heightfield:{path}:0.5").spacing == 0.5
    plain = tmp_path / "plain.npz"
    np.savez(plain, heights=GRID)
    assert parse_terrain(f"heightfield:{plain}").spacing == 1.0


# ---------------------------------------------------------------------------- samples and specs


def test_sample_elevation_size_and_relief():
    hf = sample_elevation()
    rows, cols = hf.shape
    assert (rows, cols) == (344, 403)
    x0, x1, z0, z1 = hf.extent
    assert x1 - x0 == pytest.approx(20.0)  # the longer side (columns) spans 20 m
    assert z1 - z0 == pytest.approx(20.0 * 343 / 402)
    assert x0 == pytest.approx(-x1) and z0 == pytest.approx(-z1)  # centred on the origin
    assert hf.heights.min() == 0.0
    assert hf.heights.max() == pytest.approx(SAMPLE_RELIEF_RATIO["jacksboro"] * 20.0)  # 0.56 m: true scale
    big = parse_terrain("jacksboro:40")
    assert big.extent[1] - big.extent[0] == pytest.approx(40.0)
    assert big.heights.max() == pytest.approx(2 * SAMPLE_RELIEF_RATIO["jacksboro"] * 20.0)


def test_sample_s1045():
    hf = parse_terrain("s1045:10")
    assert hf.shape == (256, 256)
    assert hf.extent[1] - hf.extent[0] == pytest.approx(10.0)
    assert hf.heights.min() == 0.0 and hf.heights.max() == pytest.approx(1.5)


def test_parse_simple_specs():
    assert parse_terrain("flat").height_m == 0.0
    assert parse_terrain(" FLAT:0.3 ").height_m == 0.3
    assert isinstance(parse_terrain("jacksboro"), HeightField)


@pytest.mark.parametrize(
    "spec, words",
    [
        ("", ["empty"]),
        ("lava", ["'lava'", "unknown kind"]),
        ("flat:high", ["'flat:high'", "number"]),
        ("flat:nan", ["finite"]),
        ("jacksboro:-3", ["'jacksboro:-3'", "> 0"]),
        ("jacksboro:abc", ["size"]),
        ("heightfield:", ["heightfield:PATH"]),
        ("heightfield:/no/such/file.npz", ["/no/such/file.npz", "not found"]),
        ("mesh:", ["mesh:PATH"]),
        ("mesh:/no/such/ground.obj", ["/no/such/ground.obj", "not found"]),
    ],
)
def test_bad_specs_raise(spec, words):
    with pytest.raises(DoodleError) as err:
        parse_terrain(spec)
    for word in words:
        assert word in str(err.value)


def test_bad_files_raise(tmp_path):
    cases = {}
    p = tmp_path / "nan.npz"
    np.savez(p, heights=np.array([[0.0, np.nan], [1.0, 2.0]]))
    cases[p] = "NaN"
    p = tmp_path / "flat1d.npz"
    np.savez(p, heights=np.arange(5.0))
    cases[p] = "2-D"
    p = tmp_path / "noheights.npz"
    np.savez(p, elevation=np.zeros((3, 3)))
    cases[p] = "no array named 'heights'"
    p = tmp_path / "corrupt.npz"
    p.write_bytes(b"PK\x03\x04 this is not a zip archive")
    cases[p] = "not a valid .npz archive"
    p = tmp_path / "pickled.npz"
    np.savez(p, heights=np.array([object()], dtype=object))
    cases[p] = "not a valid .npz archive"
    p = tmp_path / "badspacing.npz"
    np.savez(p, heights=np.zeros((3, 3)), spacing=np.array(-1.0))
    cases[p] = "spacing"
    for path, word in cases.items():
        with pytest.raises(DoodleError) as err:
            parse_terrain(f"heightfield:{path}")
        assert str(path) in str(err.value) and word in str(err.value), str(err.value)
    with pytest.raises(DoodleError, match="spacing must be > 0"):
        parse_terrain(f"heightfield:{tmp_path / 'nan.npz'}:0")
    bad_mesh = tmp_path / "broken.ply"
    bad_mesh.write_bytes(b"ply\nformat binary_little_endian 1.0\nelement vertex 99\n\x00\x01garbage")
    with pytest.raises(DoodleError) as err:
        parse_terrain(f"mesh:{bad_mesh}")
    assert str(bad_mesh) in str(err.value)
    empty = tmp_path / "empty.obj"
    empty.write_text("# nothing\n")
    with pytest.raises(DoodleError) as err:
        parse_terrain(f"mesh:{empty}")
    assert str(empty) in str(err.value)


def test_bad_arrays_raise():
    with pytest.raises(DoodleError, match="shape"):
        Flat().project(np.zeros((3, 2)))
    with pytest.raises(DoodleError, match="NaN"):
        HeightField.from_array(GRID).project([[0.0, np.nan, 0.0]])
    with pytest.raises(DoodleError, match="at least 2"):
        HeightField.from_array([[1.0, 2.0]])
    with pytest.raises(DoodleError, match="spacing"):
        HeightField.from_array(GRID, spacing=0.0)
    with pytest.raises(DoodleError, match="face indices"):
        Mesh(np.zeros((3, 3)), np.array([[0, 1, 3]]))
    with pytest.raises(DoodleError, match="vertices"):
        Mesh(np.zeros((3, 2)), np.array([[0, 1, 2]]))


def test_obj_reader_reads_what_exporters_write(tmp_path):
    """Our OBJ reader: texture/normal references, negative indices, polygons as fans, vertex
    colours, continuation lines, every other statement skipped."""
    from retarget.objfile import read_obj

    path = tmp_path / "export.obj"
    path.write_text("# Blender\nmtllib a.mtl\no Plane\nv -1 0 -1 0.5 0.5 0.5\nv 1 0 -1\nv 1 0 1 1.0\nv -1 0 1\n"
                    "vt 0 0\nvn 0 1 0\nusemtl grass\ns off\nf 1/1/1 2/1/1 \\\n 3/1/1 4/1/1\nf -4//1 -2//1 -1//1\n")
    vertices, faces = read_obj(path)
    assert vertices.shape == (4, 3) and faces.tolist() == [[0, 1, 2], [0, 2, 3], [0, 2, 3]]
    ground = parse_terrain(f"mesh:{path}")
    np.testing.assert_allclose(ground.height([[0.2, 0.3]]), [0.0])
    path.write_text("v 0 0 0\nv 1 0 0\nv 0 0 1\nf 1 2 3\nbogus 1 2\n")
    with pytest.raises(DoodleError, match=r"export.obj:5: 'bogus' is not an OBJ statement"):
        read_obj(path)
    path.write_text("v 0 0 nan\n")
    with pytest.raises(DoodleError, match=r"export.obj:1: vertex coordinate nan is not a finite number"):
        read_obj(path)
