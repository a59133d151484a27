"""htngtp.gtp: solutions, statistics, timed trajectories as numpy arrays, resulting worlds."""

import numpy as np
import pytest

import htngtp


@pytest.fixture(scope="module")
def accessible(world):
    return htngtp.gtp(world, "make-accessible", ["grey-book", "member"], seed=1, solutions=2)


def test_solutions_carry_summary_stats_and_world(world, accessible):
    assert 1 <= len(accessible) <= 2
    first = accessible[0]
    assert first.summary["task"] == "make-accessible"
    assert first.summary["args"] == ["grey-book", "member"]
    assert first.summary["placement"] is not None
    assert first.stats["solutions"] == 1 and first.stats["planner_calls"] > 0
    assert accessible.stats["solutions"] == len(accessible)
    assert [s.summary["index"] for s in accessible] == list(range(len(accessible)))
    # The solution's world has the book moved; the world asked about is unchanged.
    before = world.object_pose("grey-book").position
    after = first.world.object_pose("grey-book").position
    assert np.linalg.norm(after - before) > 0.05
    np.testing.assert_allclose(world.object_pose("grey-book").position, before)


def test_trajectories_are_numpy_arrays_of_consistent_shapes(accessible):
    trajectories = accessible[0].trajectories
    assert trajectories, "a make-accessible solution moves the arm"
    for t in trajectories:
        dof = len(t.joint_names)
        assert dof > 0
        assert t.positions.dtype == np.float64
        assert t.positions.ndim == 2 and t.positions.shape[1] == dof
        n = t.positions.shape[0]
        assert t.velocities.shape == (n, dof)
        assert t.time_from_start.shape == (n,)
        assert t.waypoints.shape[1] == dof
        assert len(t.velocity_limits) == dof == len(t.acceleration_limits)


def test_trajectories_are_timed_rest_to_rest_within_limits(accessible):
    for t in accessible[0].trajectories:
        if len(t.time_from_start) < 2:
            continue
        assert t.time_from_start[0] == 0.0
        assert np.all(np.diff(t.time_from_start) > 0)
        np.testing.assert_allclose(t.velocities[0], 0.0, atol=1e-9)
        np.testing.assert_allclose(t.velocities[-1], 0.0, atol=1e-9)
        limits = np.asarray(t.velocity_limits)
        assert np.all(np.abs(t.velocities) <= limits * (1 + 1e-6))
        # The points pass through the planner's first and last waypoints.
        np.testing.assert_allclose(t.positions[0], t.waypoints[0], atol=1e-6)
        np.testing.assert_allclose(t.positions[-1], t.waypoints[-1], atol=1e-6)
        assert t.duration == pytest.approx(t.time_from_start[-1])


def test_the_same_seed_gives_the_same_solution(world, accessible):
    again = htngtp.gtp(world, "make-accessible", ["grey-book", "member"], seed=1)
    a, b = accessible[0].trajectories, again[0].trajectories
    assert [t.joint_names for t in a] == [t.joint_names for t in b]
    for x, y in zip(a, b):
        np.testing.assert_array_equal(x.positions, y.positions)


def test_a_solution_world_can_be_planned_on(accessible):
    # After make-accessible the robot holds nothing; picking the book again is possible.
    result = htngtp.gtp(accessible[0].world, "pick", ["grey-book"], seed=2)
    assert result[0].world.holder("grey-book") is not None


def test_no_solution_raises_unsolvable(world):
    # Nowhere on the furniture can the member reach the book without moving (effort 0).
    with pytest.raises(htngtp.Unsolvable) as e:
        htngtp.gtp(world, "make-accessible", ["grey-book", "member"], settings={"reach-within": 0})
    assert "make-accessible(grey-book, member)" in str(e.value)
    assert "reachable by member at effort <= 0" in str(e.value)
    assert e.value.stats["solutions"] == 0


def test_the_time_limit_raises_limit_reached(world):
    with pytest.raises(htngtp.LimitReached) as e:
        htngtp.gtp(world, "give", ["white-book", "member"], time_limit=1e-6)
    assert e.value.limit == "time"


def test_bad_requests_raise_value_error(world):
    with pytest.raises(ValueError, match="fly"):
        htngtp.gtp(world, "fly", ["grey-book"])
    with pytest.raises(ValueError):
        htngtp.gtp(world, "pick", ["unicorn"])
    with pytest.raises(ValueError):
        htngtp.gtp(world, "pick", ["grey-book"], solutions=0)
    with pytest.raises(TypeError):
        htngtp.gtp(world, "pick", "grey-book")
