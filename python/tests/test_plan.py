"""htngtp.plan: symbolic and combined planning, the plan's parts, its JSON and re-check, and
the typed exceptions."""

import json

import numpy as np
import pytest

import htngtp
from conftest import (
    COUNTER_DOMAIN,
    COUNTER_PROBLEM,
    DELIVERY_DOMAIN,
    DELIVERY_PROBLEM,
    LIBRARY,
    SCENE,
    UNSOLVABLE_PROBLEM,
)


def test_a_symbolic_plan_has_steps_tree_and_stats(hddl):
    plan = htngtp.plan(hddl("d.hddl", DELIVERY_DOMAIN), hddl("p.hddl", DELIVERY_PROBLEM))
    assert [(s.action, s.args) for s in plan.steps] == [
        ("load", ["box", "depot"]),
        ("drive", ["depot", "shop"]),
        ("unload", ["box", "shop"]),
    ]
    assert all(s.gtp is None and s.trajectories == [] for s in plan.steps)
    (root,) = plan.root
    top = plan.tree[root]
    assert top.task == "deliver" and top.method == "m-deliver" and top.args == ["box", "shop"]
    assert [plan.tree[c].action for c in top.children] == ["load", "drive", "unload"]
    assert plan.stats["nodes"] > 0 and plan.stats["time_ms"] >= 0
    assert plan.plan_text.startswith("==>") and "root" in plan.plan_text
    data = json.loads(plan.to_json())
    assert data["format"] == "htngtp-plan" and data["status"] == "solved"
    assert data["scene"] is None
    report = plan.check()
    assert report.clean and report.faults == []


def test_the_same_seed_gives_the_same_plan(hddl):
    d, p = hddl("d.hddl", DELIVERY_DOMAIN), hddl("p.hddl", DELIVERY_PROBLEM)
    assert htngtp.plan(d, p, seed=3).plan_text == htngtp.plan(d, p, seed=3).plan_text


def test_a_parse_error_names_file_line_and_column(hddl):
    broken = DELIVERY_DOMAIN.replace("(:action drive", "(:action drive :bogus-key", 1)
    domain = hddl("broken.hddl", broken)
    with pytest.raises(htngtp.ParseError) as e:
        htngtp.plan(domain, hddl("p.hddl", DELIVERY_PROBLEM))
    err = e.value
    assert err.file.endswith("broken.hddl")
    line = broken.splitlines().index(
        next(x for x in broken.splitlines() if ":bogus-key" in x)
    ) + 1
    assert err.line == line and err.column > 0
    assert str(err).startswith(f"{err.file}:{err.line}:{err.column}: ")
    assert isinstance(err, htngtp.HtngtpError) and isinstance(err, ValueError)


def test_a_missing_file_is_a_parse_error_without_position(tmp_path, hddl):
    with pytest.raises(htngtp.ParseError) as e:
        htngtp.plan(tmp_path / "none.hddl", hddl("p.hddl", DELIVERY_PROBLEM))
    assert e.value.line == 0 and e.value.column == 0


def test_no_plan_raises_unsolvable(hddl):
    with pytest.raises(htngtp.Unsolvable) as e:
        htngtp.plan(hddl("d.hddl", DELIVERY_DOMAIN), hddl("p.hddl", UNSOLVABLE_PROBLEM))
    assert "no plan exists" in str(e.value)
    assert e.value.stats["nodes"] >= 1


def test_a_node_limit_raises_limit_reached(hddl):
    with pytest.raises(htngtp.LimitReached) as e:
        htngtp.plan(hddl("d.hddl", COUNTER_DOMAIN), hddl("p.hddl", COUNTER_PROBLEM), node_limit=50)
    assert e.value.limit == "nodes"
    assert e.value.stats["nodes"] >= 50


def test_a_time_limit_raises_limit_reached(hddl):
    with pytest.raises(htngtp.LimitReached) as e:
        htngtp.plan(hddl("d.hddl", COUNTER_DOMAIN), hddl("p.hddl", COUNTER_PROBLEM), time_limit=0.2)
    assert e.value.limit == "time"


def test_bad_arguments_raise_value_error(hddl):
    d, p = hddl("d.hddl", DELIVERY_DOMAIN), hddl("p.hddl", DELIVERY_PROBLEM)
    with pytest.raises(ValueError, match="strategy"):
        htngtp.plan(d, p, strategy="random")
    with pytest.raises(ValueError, match="time_limit"):
        htngtp.plan(d, p, time_limit=0)


def test_geometric_tasks_need_a_scene():
    with pytest.raises(ValueError, match="geometric back end"):
        htngtp.plan(LIBRARY / "domain-compound.hddl", LIBRARY / "fig4.hddl")


def test_an_invalid_scene_raises_scene_error(tmp_path):
    bad = tmp_path / "scene.toml"
    bad.write_text("not toml [")
    with pytest.raises(htngtp.SceneError):
        htngtp.plan(LIBRARY / "domain-compound.hddl", LIBRARY / "fig4.hddl", scene=bad)


def test_the_demo_plan_has_geometric_steps_with_timed_trajectories(demo_plan):
    gs = [s for s in demo_plan.steps if s.gtp]
    assert gs, "the demo has GS actions"
    assert {s.gtp["task"] for s in gs} >= {"pick-and-make-accessible"}
    assert any(s.added for s in gs)
    for s in gs:
        assert s.trajectories
        for t in s.trajectories:
            dof = len(t.joint_names)
            n = len(t.time_from_start)
            assert t.positions.shape == (n, dof) and t.velocities.shape == (n, dof)
            assert t.time_from_start.shape == (n,)
            assert t.time_from_start[0] == 0.0 and np.all(np.diff(t.time_from_start) > 0)
            if t.gripper_joint is not None:
                assert t.gripper_position.shape == (n,)
    assert demo_plan.stats["gtp_tasks"]
    assert demo_plan.trajectories == [t for s in demo_plan.steps for t in s.trajectories]


def test_the_demo_plan_passes_the_independent_check(demo_plan):
    report = demo_plan.check()
    assert report.clean, report.faults
    assert report.details["trajectories"] == len(demo_plan.trajectories)
    assert report.details["kinematics_max_mm"] < 1.0


def test_the_demo_plan_json_round_trips(demo_plan, tmp_path):
    path = tmp_path / "plan.json"
    demo_plan.write(path)
    data = json.loads(path.read_text())
    assert data["status"] == "solved"
    assert len(data["steps"]) == len(demo_plan.steps)
    assert data == json.loads(demo_plan.to_json())
    again = htngtp.Plan(demo_plan.to_json(), LIBRARY / "domain-compound.hddl", LIBRARY / "fig4.hddl", SCENE)
    assert again.plan_text == demo_plan.plan_text
