"""Trajectory transfer (§5.2): projection, in-place merging with a running offset, jump
retiming and the beautified Hermite arcs, heading; a walk or a jump the doodle asks faster
than a character can go."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from retarget.terrain import parse_terrain
from retarget.trajectory import JUMP_SPEED_MOST, Span, hermite_arc, jump_reach, limited, overspeed, travel_share, world_path


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


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 10_000), st.floats(0.5, 6.0))
def test_a_limited_walk_keeps_to_the_path_never_faster_and_never_ahead(seed, most):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(2, 200))
    t = np.cumsum(rng.uniform(0.005, 0.02, n))
    path = np.cumsum(rng.normal(0.0, 0.05, (n, 3)) * rng.uniform(0.1, 3.0), axis=0)
    path[:, 1] = 0.0
    held = limited(t, path, most)
    step = np.hypot(*np.diff(path[:, [0, 2]], axis=0).T)
    if np.all(step <= most * np.diff(t)):
        assert held is path  # a walk it can keep to is left as it is
        return
    moved = np.hypot(*np.diff(held[:, [0, 2]], axis=0).T)
    assert np.all(moved <= most * np.diff(t) + 1e-9)  # never faster than it can walk
    covered, asked = np.cumsum(moved), np.cumsum(step)
    assert np.all(covered <= asked + 1e-9)  # never ahead of the doodle
    assert np.array_equal(held[0], path[0])
    # on the doodle's own path: each point lies on a segment between two doodle samples
    a, d = path[:-1], np.diff(path, axis=0)
    w = np.clip(np.einsum("pkj,kj->pk", held[:, None] - a[None], d) / np.maximum((d * d).sum(axis=1), 1e-300), 0, 1)
    gap = np.linalg.norm(held[:, None] - (a[None] + w[..., None] * d[None]), axis=2).min(axis=1)
    assert gap.max() < 1e-9


def test_a_walk_too_fast_falls_behind_and_the_rest_follows_from_where_it_got_to():
    rate = 90.0
    t = np.arange(270) / rate
    p = np.column_stack([np.zeros(270), np.zeros(270), np.zeros(270)])
    p[90:200, 2] = np.arange(110) / 90.0  # 0.1 m of doodle in 0.1 s, and on into the Idle: 10 m/s at scale 10
    p[200:, 2] = p[199, 2]
    spans = [Span("Idle", 0.0, 89 / rate, 0, 90, True, False, True),
             Span("Walk", 90 / rate, 179 / rate, 90, 180, False, False, True, most_speed=4.0),
             Span("Idle", 180 / rate, 269 / rate, 180, 270, True, False, True)]
    path, _ = world_path(t, p, spans, scale=10.0)
    speed = np.hypot(*np.diff(path[:, [0, 2]], axis=0).T) * rate
    assert speed.max() <= 4.0 + 1e-9
    assert path[179, 2] == pytest.approx(4.0 * 89 / rate, rel=0.02)  # as far as 4 m/s goes in the walk
    assert np.ptp(path[180:, 2]) == 0.0 and np.allclose(path[180], path[179], rtol=0, atol=1e-12)  # stands where it got to
    (span, asked, most, behind), = overspeed(t, p, spans, 10.0)
    assert span.action == "Walk" and asked == pytest.approx(10.0, rel=0.02) and most == 4.0
    assert behind == pytest.approx(10.0 * 89 / rate - 4.0 * 89 / rate, rel=0.02)
    slow = [s if s.action != "Walk" else Span("Walk", s.t0, s.t1, s.i0, s.i1, False, False, True, most_speed=20.0)
            for s in spans]
    assert overspeed(t, p, slow, 10.0) == []
    unlimited, _ = world_path(t, p, slow, scale=10.0)
    assert unlimited[179, 2] == pytest.approx(10.0 * p[179, 2])  # a walk it can keep to is the doodle's
    assert unlimited[180, 2] - unlimited[179, 2] == pytest.approx(10.0 / rate)  # and on, one doodle step


def test_a_jump_farther_than_its_flight_can_carry_lands_short_the_way_it_jumped():
    t, p, spans = doodle_with(lambda r: [("Walk", 0, 90, False, False), ("Jump", 90, 180, False, True),
                                         ("Walk", 180, 270, False, False)])
    p = p.copy()
    p[90:180, 0] = np.linspace(0.0, 3.0, 90)  # 3 m sideways in the jump: 30 m at scale 10
    p[180:, 0] = 3.0
    path, _ = world_path(t, p, spans, scale=10.0)
    flight = (spans[1].t1 - spans[1].t0) * 0.2  # execution (0.4, 0.6) of the span
    leap = path[179] - path[90]
    reach = JUMP_SPEED_MOST * flight
    assert np.hypot(leap[0], leap[2]) == pytest.approx(reach, rel=1e-6)
    asked = 10.0 * (p[179] - p[90])
    assert np.allclose(leap[[0, 2]] / np.hypot(*leap[[0, 2]]), asked[[0, 2]] / np.hypot(*asked[[0, 2]]))
    assert np.allclose(path[180], path[179], rtol=0, atol=1e-12)  # the walk after it starts where it landed
    (span, far, most, short), = overspeed(t, p, spans, 10.0)
    assert span.action == "Jump" and most == pytest.approx(reach) and short == pytest.approx(far - reach)


@settings(max_examples=60, deadline=None)
@given(st.floats(0.05, 0.6), st.floats(0.05, 0.4), st.floats(0.0, 0.3), st.floats(0.0, 0.3))
def test_a_jump_gathers_its_speed_on_the_ground_and_keeps_it_in_the_air(a, flight, r0, r1):
    """The share of a jump's travel: none before its push-off, all after its landing, an even
    speed through the flight, gathered and shed at an even rate either side — the speed never
    stepping (the character stopped in one frame at touch-down)."""
    b = min(a + flight, 0.95)
    span = Span("Jump", 0.0, 1.0, 0, 2, False, True, False, (a, b), ramps=(r0, r1))
    r0, r1 = min(r0, a), min(r1, 1.0 - b)
    u = np.linspace(0.0, 1.0, 20001)
    w = travel_share(u, span)
    assert w[0] < 1e-12 and w[-1] == pytest.approx(1.0) and np.all(np.diff(w) >= -1e-12)
    assert np.all(w[u <= a - r0] < 1e-12) and np.allclose(w[u >= b + r1], 1.0)
    speed = np.diff(w) / np.diff(u)
    top = 1.0 / (b - a + 0.5 * (r0 + r1))
    inside = (u[1:] > a + 1e-3) & (u[:-1] < b - 1e-3)
    assert np.allclose(speed[inside], top, rtol=1e-3)  # even in the air
    assert speed.max() <= top * (1 + 1e-3)
    if min(r0, r1) > 0.01:  # no step anywhere: the speed changes at most at the ramps' even rate
        assert np.abs(np.diff(speed)).max() <= top * (1e-3 + (u[1] - u[0]) / min(r0, r1))
    t = np.linspace(0.0, 2.0, 5)
    assert jump_reach(t, span) == pytest.approx(JUMP_SPEED_MOST * 2.0 / top)  # the flight no faster than the most


def test_without_ramps_a_jump_travels_over_its_flight_alone():
    span = Span("Jump", 0.0, 1.0, 0, 2, False, True, False, (0.3, 0.7))
    u = np.linspace(0.0, 1.0, 101)
    np.testing.assert_allclose(travel_share(u, span), np.clip((u - 0.3) / 0.4, 0.0, 1.0), atol=1e-12)
