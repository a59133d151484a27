"""htngtp.World: loading, names, poses, joint values, shared literals, pictures, errors."""

import numpy as np
import pytest

import htngtp
from conftest import SCENE


def test_load_lists_objects_and_agents(world):
    assert {"grey-book", "white-book", "pos-machine", "desk"} <= set(world.objects)
    assert world.agents == ["pr2", "member"]
    assert world.agent_kind("pr2") == "robot"
    assert world.agent_kind("member") == "human"
    assert world.is_movable("grey-book") and not world.is_movable("desk")
    assert "World" in repr(world)


def test_poses_are_numpy_position_and_unit_quaternion(world):
    pose = world.object_pose("grey-book")
    assert pose.position.shape == (3,) and pose.quaternion.shape == (4,)
    assert np.isclose(np.linalg.norm(pose.quaternion), 1.0, atol=1e-5)
    base = world.agent_pose("pr2")
    assert base.position.shape == (3,)
    poses = world.object_poses()
    assert set(poses) == set(world.objects)
    np.testing.assert_allclose(poses["grey-book"].position, pose.position)


def test_joint_positions_include_the_planar_base(world):
    joints = world.joint_positions("pr2")
    assert {"base_x", "base_y", "base_yaw"} <= set(joints)
    base = world.agent_pose("pr2").position
    assert joints["base_x"] == pytest.approx(base[0], abs=1e-6)
    assert joints["base_y"] == pytest.approx(base[1], abs=1e-6)
    assert any(name.startswith("r_shoulder") for name in joints)


def test_nothing_is_held_at_the_start(world):
    assert world.holder("grey-book") is None


def test_facts_give_visibility_and_reach_with_effort_levels(world):
    facts = world.facts()
    predicates = {f.predicate for f in facts}
    assert {"visible", "reachable", "on"} <= predicates
    for f in facts:
        if f.predicate in ("visible", "reachable"):
            assert len(f.args) == 2 and f.args[1] in world.agents
            assert f.effort is not None and 0 <= f.effort <= 4
        else:
            assert f.effort is None
    assert any(f.predicate == "on" and f.args[0] == "grey-book" for f in facts)


def test_facts_refuse_a_bad_threshold(world):
    with pytest.raises(ValueError, match="threshold"):
        world.facts(threshold=0.0)


@pytest.mark.parametrize("view", ["top", "human", "pr2"])
def test_render_writes_a_png(world, tmp_path, view):
    path = tmp_path / f"{view}.png"
    world.render(view, path, width=64)
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    assert len(data) > 100


def test_render_refuses_an_unknown_view(world, tmp_path):
    with pytest.raises(ValueError, match="unknown view"):
        world.render("ceiling", tmp_path / "x.png", width=32)


def test_unknown_names_raise_value_error(world):
    with pytest.raises(ValueError, match="no object `unicorn`"):
        world.object_pose("unicorn")
    with pytest.raises(ValueError, match="no agent `nobody`"):
        world.joint_positions("nobody")


def test_an_invalid_scene_raises_scene_error(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text("[scene]\nname = 3\n")
    with pytest.raises(htngtp.SceneError) as e:
        htngtp.World.load(bad)
    assert "bad.toml" in str(e.value)
    assert isinstance(e.value, htngtp.HtngtpError) and isinstance(e.value, ValueError)


def test_a_missing_scene_raises_scene_error(tmp_path):
    with pytest.raises(htngtp.SceneError):
        htngtp.World.load(tmp_path / "missing.toml")


def test_load_accepts_path_objects_and_strings():
    assert htngtp.World.load(str(SCENE)).objects == htngtp.World.load(SCENE).objects
