"""Trajectory transfer (§5.2): projection, in-place merging with a running offset, jump
retiming and the beautified Hermite arcs, heading."""

import numpy as np
import pytest

from retarget.terrain import parse_terrain
from retarget.trajectory import Span, hermite_arc, world_path


def test_hermite_arc_is_vertical_at_both_ends_with_the_thesis_apex():
    s, e = np.array([0.0, 0.0, 0.0]), np.array([0.0, 0.0, 2.0])
    w = np.linspace(0, 1, 1001)
    arc = hermite_arc(s, e, w)
    assert np.allclose(arc[0], s) and np.allclose(arc[-1], e)
    assert arc[500, 1] == pytest.approx(2.5 * 2.0 / 4)  # α‖e − s‖/4 at the middle
    d0, d1 = arc[1] - arc[0], arc[-1] - arc[-2]
    assert abs(d0[2]) < 1e-2 * d0[1] and d0[1] > 0 and d1[1] < 0  # up at take-off, down at landing
    assert hermite_arc(s, e, np.array([0.5]), apex=0.4)[0, 1] == pytest.approx(0.4)


def doodle_with(spans_spec, rate=90.0):
    """A straight forward doodle (0.1 m/s along +z) with a hop in the middle (up 5 cm)."""
    n = int(3 * rate)
    t = np.arange(n) / rate
    p = np.column_stack([np.zeros(n), np.zeros(n), 0.1 * t])
    hop = (t > 1.0) & (t < 2.0)
    p[hop, 1] = 0.05 * np.sin(np.pi * (t[hop] - 1.0))
    spans = [Span(a, i0 / rate, (i1 - 1) / rate, i0, i1, in_place, jumping, False, (0.4, 0.6))
             for a, i0, i1, in_place, jumping in spans_spec(rate)]
    return t, p, spans


def test_in_place_action_is_merged_and_the_path_stays_continuous():
    t, p, spans = doodle_with(lambda r: [("Walk", 0, 90, False, False), ("Stomp", 90, 180, True, False),
                                         ("Walk", 180, 270, False, False)])
    path, _ = world_path(t, p, spans, scale=10.0)
    assert np.ptp(path[90:180], axis=0).max() == 0.0  # merged into its first point
    steps = np.linalg.norm(np.diff(path, axis=0), axis=1)
    assert steps.max() < 0.02  # no jump where the offset is applied
    assert path[-1, 2] == pytest.approx(10.0 * (p[-1, 2] - p[0, 2]) - 10.0 * (p[179, 2] - p[90, 2]), abs=0.02)


@pytest.mark.parametrize("mode", ["clip", "hermite", "apex"])
def test_jump_travels_during_execution_and_arcs(mode):
    t, p, spans = doodle_with(lambda r: [("Walk", 0, 90, False, False), ("Jump", 90, 180, False, True),
                                         ("Walk", 180, 270, False, False)])
    path, _ = world_path(t, p, spans, scale=10.0, jump_arc=mode)
    jump = path[90:180]
    u = np.linspace(0, 1, 90)
    before, after = u < 0.39, u > 0.61
    assert np.ptp(jump[before][:, 2]) < 1e-9 and np.ptp(jump[after][:, 2]) < 1e-9  # waits, then rests
    assert jump[after][0, 2] > jump[before][0, 2] + 0.5
    lift = jump[:, 1]
    assert np.allclose(lift[before], 0) and np.allclose(lift[after], 0)
    if mode == "clip":
        assert np.allclose(lift, 0)
    elif mode == "apex":
        assert lift.max() == pytest.approx(10.0 * 0.05, rel=0.05)  # the doodle's apex, scaled
    else:
        assert lift.max() > 0.5


def test_path_lies_on_the_terrain_and_faces_its_way():
    t, p, spans = doodle_with(lambda r: [("Walk", 0, 270, False, False)])
    terrain = parse_terrain("jacksboro")
    path, heading = world_path(t, p, spans, scale=10.0, terrain=terrain)
    assert np.allclose(path[:, 1], terrain.height(path[:, [0, 2]]))
    assert np.allclose(heading[10:-10], 0.0, atol=1e-6)  # walking along +z faces +z
