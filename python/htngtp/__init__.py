"""htngtp: combined HTN and geometric task planning (de Silva, Pandey, Gharbi and Alami,
*Towards Combining HTN Planning and Geometric Task Planning*) from Python.

- :class:`World` -- a 3D scene: its objects, agents and their poses, its shared literals
  (:meth:`World.facts`), pictures (:meth:`World.render`).
- :func:`gtp` -- one geometric task (pick, place-on, show, give, take, make-accessible,
  put-away, navigate-to, pick-and-make-accessible): solutions with their summary, statistics,
  timed joint trajectories as numpy arrays, and the world each leaves.
- :func:`plan` -- HTN planning of HDDL files, the geometric tasks answered by the GTP in a
  scene when one is given: the validated plan with its steps, decomposition tree, statistics,
  plan JSON (:meth:`Plan.to_json`) and independent re-check (:meth:`Plan.check`).

Failures raise :class:`ParseError`, :class:`SceneError`, :class:`LimitReached` or
:class:`Unsolvable` (all :class:`HtngtpError`); bad arguments raise ``ValueError``.
The Rust code runs without the GIL.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from typing import Any, Dict, Iterator, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

from . import _native
from .errors import HtngtpError, LimitReached, ParseError, SceneError, Unsolvable

PathLike = Union[str, "os.PathLike[str]"]

#: Acceleration limit (rad/s^2 or m/s^2) of every arm joint whose URDF declares none.
DEFAULT_JOINT_ACCELERATION: float = _native.DEFAULT_JOINT_ACCELERATION

__all__ = [
    "World",
    "Pose",
    "Fact",
    "Trajectory",
    "Solution",
    "GtpResult",
    "Step",
    "TreeNode",
    "Plan",
    "CheckReport",
    "gtp",
    "plan",
    "HtngtpError",
    "ParseError",
    "SceneError",
    "LimitReached",
    "Unsolvable",
    "DEFAULT_JOINT_ACCELERATION",
]


@dataclass(frozen=True)
class Pose:
    """A pose in the world frame: ``position`` (3,) in metres and ``quaternion`` (4,) as
    (x, y, z, w)."""

    position: np.ndarray
    quaternion: np.ndarray


@dataclass(frozen=True)
class Fact:
    """A shared literal: ``predicate`` (visible, reachable, on, inside, covered-by), ``args``,
    and for visible/reachable the least ``effort`` level at which it holds (0 in view / in
    hand ... 4 walk or drive), else None."""

    predicate: str
    args: Tuple[str, ...]
    effort: Optional[int]


def _pose(parts: Tuple[Sequence[float], Sequence[float]]) -> Pose:
    return Pose(np.asarray(parts[0], dtype=float), np.asarray(parts[1], dtype=float))


class World:
    """A 3D world: a scene's furniture, movable objects and agents (robot and people) in their
    current poses. Load one with :meth:`World.load`; :func:`gtp` returns the world each
    solution leaves. Worlds are immutable from Python."""

    __slots__ = ("_native",)

    def __init__(self, native: "_native.World") -> None:
        self._native = native

    @classmethod
    def load(cls, scene: PathLike, allow_initial_contact: bool = False) -> "World":
        """Loads a scene file (TOML, docs/scene-format.md). Raises :class:`SceneError` when
        the file is invalid or starts in collision; with ``allow_initial_contact`` objects
        that start inside one another are read anyway (never a robot inside furniture)."""
        return cls(_native.World.load(os.fspath(scene), allow_initial_contact))

    @property
    def objects(self) -> List[str]:
        """The objects' names (furniture and movable objects), in scene order."""
        return self._native.objects()

    @property
    def agents(self) -> List[str]:
        """The agents' names (robot and people), in scene order."""
        return self._native.agents()

    def is_movable(self, name: str) -> bool:
        """Whether object ``name`` is movable (a book) rather than furniture."""
        return self._native.movable(name)

    def agent_kind(self, name: str) -> str:
        """``"robot"`` or ``"human"``."""
        return self._native.agent_kind(name)

    def object_pose(self, name: str) -> Pose:
        """The pose of object ``name``. Raises ValueError for an unknown name."""
        return _pose(self._native.object_pose(name))

    def object_poses(self) -> Dict[str, Pose]:
        """The pose of every object, by name."""
        return {n: self.object_pose(n) for n in self.objects}

    def agent_pose(self, name: str) -> Pose:
        """The pose of agent ``name``'s base. Raises ValueError for an unknown name."""
        return _pose(self._native.agent_pose(name))

    def joint_positions(self, agent: str) -> Dict[str, float]:
        """Every joint value of ``agent`` by joint name (rad or m), the planar base's
        ``base_x``, ``base_y`` and ``base_yaw`` included."""
        return dict(self._native.joint_positions(agent))

    def holder(self, name: str) -> Optional[Tuple[str, str]]:
        """``(agent, link)`` holding object ``name``, or None when it is not held."""
        return self._native.holder(name)

    def facts(self, threshold: float = 0.5, resolution: int = 64) -> List[Fact]:
        """The shared literals this world makes true, as ``htngtp facts`` (the paper's Fig. 5):
        for every agent and movable object the least effort level at which the agent sees it
        (at least ``threshold`` of its pixels on a ``resolution`` x ``resolution`` grid) and
        reaches it, then on / inside / covered-by among objects."""
        raw = json.loads(self._native.facts_json(threshold, resolution))
        return [Fact(f["predicate"], tuple(f["args"]), f["effort"]) for f in raw]

    def render(
        self,
        view: str,
        path: PathLike,
        width: int = 800,
        height: Optional[int] = None,
        look_at: Optional[str] = None,
    ) -> None:
        """Draws the world into the PNG file ``path`` with the CPU ray caster. ``view`` is
        ``"top"`` (from above), ``"human"`` (the first person's eyes), ``"robot"`` (the robot's
        camera) or an agent's name; ``look_at`` turns that agent's head towards an object
        first. ``height`` defaults to the view's aspect ratio."""
        self._native.render(view, os.fspath(path), width, height, look_at)

    def __repr__(self) -> str:
        return repr(self._native)


@dataclass(frozen=True)
class Trajectory:
    """One timed joint trajectory (the fields of ROS's ``trajectory_msgs/JointTrajectory``):
    ``positions`` (T, dof) and ``velocities`` (T, dof) per point, in the order of
    ``joint_names``, and ``time_from_start`` (T,) in seconds, rest to rest within the joints'
    velocity and acceleration limits. ``group`` is the arm (``right_arm``, ``left_arm``, a
    person's hand) or ``base`` (joints ``base_x``, ``base_y``, ``base_yaw``); ``phase`` is the
    motion's label (approach, grasp, lift, transfer, place, retreat, ...); ``waypoints``
    (W, dof) is the planner's path that the points pass through. ``gripper_position`` (T,) is
    the gripper joint per point in a plan's trajectories (None for one :func:`gtp` call)."""

    agent: str
    group: str
    phase: str
    holding: Optional[str]
    joint_names: List[str]
    positions: np.ndarray
    velocities: np.ndarray
    time_from_start: np.ndarray
    waypoints: np.ndarray
    velocity_limits: List[float]
    acceleration_limits: List[float]
    gripper_joint: Optional[str] = None
    gripper_position: Optional[np.ndarray] = None

    @property
    def duration(self) -> float:
        """Seconds from the first point to the last."""
        return float(self.time_from_start[-1]) if len(self.time_from_start) else 0.0


@dataclass(frozen=True)
class Solution:
    """One solution of a GTP call: ``summary`` (grasp, placement, visibility, reach effort,
    the trajectories' phases, joints and lengths, as ``htngtp gtp --json`` without the
    waypoints, which are each :class:`Trajectory`'s ``waypoints``), ``stats`` (what producing
    this solution took: the paper's Table II columns), the timed ``trajectories``, and the
    ``world`` after it."""

    summary: Dict[str, Any]
    stats: Dict[str, Any]
    trajectories: List[Trajectory]
    world: World


@dataclass(frozen=True)
class GtpResult:
    """The solutions of one :func:`gtp` call (at least one; fewer than asked when the stream
    ended, ``failure`` then says why), and the call's cumulative ``stats``. Iterating,
    indexing and ``len`` go over the solutions."""

    task: str
    args: Tuple[str, ...]
    solutions: List[Solution]
    stats: Dict[str, Any]
    failure: Optional[Dict[str, Any]]

    def __iter__(self) -> Iterator[Solution]:
        return iter(self.solutions)

    def __len__(self) -> int:
        return len(self.solutions)

    def __getitem__(self, i: int) -> Solution:
        return self.solutions[i]


def _trajectory(d: Mapping[str, Any]) -> Trajectory:
    return Trajectory(
        agent=d["agent"],
        group=d["group"],
        phase=d["phase"],
        holding=d["holding"],
        joint_names=list(d["joint_names"]),
        positions=d["positions"],
        velocities=d["velocities"],
        time_from_start=d["time_from_start"],
        waypoints=d["waypoints"],
        velocity_limits=list(d["velocity_limits"]),
        acceleration_limits=list(d["acceleration_limits"]),
    )


def _gtp_result(task: str, args: Sequence[str], raw: Mapping[str, Any]) -> GtpResult:
    """The :class:`GtpResult` of the native module's answer; raises :class:`Unsolvable` or
    :class:`LimitReached` when it has no solution."""
    stats = json.loads(raw["stats"])
    failure = json.loads(raw["failure"]) if raw["failure"] else None
    found = [
        Solution(
            summary=json.loads(s["summary"]),
            stats=json.loads(s["stats"]),
            trajectories=[_trajectory(t) for t in s["trajectories"]],
            world=World(s["world"]),
        )
        for s in raw["solutions"]
    ]
    if not found:
        what = f"{task}({', '.join(args)})"
        why = failure["message"] if failure else "no solution"
        if failure and failure.get("limit"):
            raise LimitReached(f"{what}: {why}", "time", json.dumps(stats))
        raise Unsolvable(f"{what}: no solution: {why}", json.dumps(stats))
    return GtpResult(task, tuple(args), found, stats, failure)


def gtp(
    world: World,
    task: str,
    args: Sequence[str],
    seed: int = 1,
    solutions: int = 1,
    time_limit: Optional[float] = None,
    settings: Optional[Mapping[str, Any]] = None,
    max_acceleration: float = DEFAULT_JOINT_ACCELERATION,
) -> GtpResult:
    """Runs one geometric task in ``world`` (which is not changed) and pulls up to
    ``solutions`` solutions, each different from the ones before, as ``htngtp gtp``.

    Tasks and arguments: ``pick OBJECT``; ``place-on OBJECT SUPPORT``; ``show``, ``give``,
    ``take``, ``make-accessible``, ``put-away``, ``pick-and-make-accessible`` ``OBJECT HUMAN``;
    ``navigate-to TARGET``. ``settings`` overrides thresholds (min-visibility, max-visibility,
    reach-within, unreachable-within, max-effort, robot-effort, lift, approach, time-limit,
    max-points);
    ``time_limit`` (s) bounds the call (60 s by default). The same seed gives the same
    solutions. Trajectories are timed as the plan JSON's (``max_acceleration`` for joints whose
    URDF declares no acceleration limit).

    Raises :class:`Unsolvable` when the task has no solution (the message names the constraint
    that stopped the search), :class:`LimitReached` when the time limit stopped it first, and
    ValueError for an unknown task, object or agent, or a bad setting.
    """
    if isinstance(args, str):
        raise TypeError("args must be a sequence of names, not one string")
    if solutions < 1:
        raise ValueError(f"solutions must be at least 1, got {solutions}")
    kv = [(str(k), str(v)) for k, v in (settings or {}).items()]
    raw = _native.gtp(
        world._native,
        task,
        [str(a) for a in args],
        seed,
        solutions,
        kv,
        time_limit,
        max_acceleration,
    )
    return _gtp_result(task, args, raw)


@dataclass(frozen=True)
class Step:
    """One primitive action of a plan, in order: ``index``, ``id`` (the competition plan's),
    ``action`` and ``args``; for a GS action, ``gtp`` (its task, args, summary, stats), the
    shared literals it ``added`` and ``deleted``, and its timed ``trajectories`` (played in
    order); ``object_poses`` are the movable objects' poses after it."""

    index: int
    id: int
    action: str
    args: List[str]
    added: List[List[str]]
    deleted: List[List[str]]
    gtp: Optional[Dict[str, Any]]
    trajectories: List[Trajectory]
    object_poses: Dict[str, Pose]


@dataclass(frozen=True)
class TreeNode:
    """A node of the decomposition tree: a compound ``task`` with its ``method`` and
    ``children`` (ids), or a primitive ``action`` with its ``step`` index."""

    id: int
    args: List[str]
    task: Optional[str] = None
    method: Optional[str] = None
    children: List[int] = field(default_factory=list)
    action: Optional[str] = None
    step: Optional[int] = None


@dataclass(frozen=True)
class CheckReport:
    """The verdict of :meth:`Plan.check`: ``clean`` when ``faults`` is empty. For a plan with a
    scene, ``details`` is ``htngtp check --json``'s report (collisions over interpolated
    frames, rest, literals re-measured, timing limits, continuity, frames against the forward
    kinematics); for a symbolic plan, the HDDL validator's verdict."""

    clean: bool
    faults: List[Any]
    details: Dict[str, Any]


def _points_trajectory(t: Mapping[str, Any]) -> Optional[Trajectory]:
    jt = t.get("joint_trajectory")
    if not jt:
        return None
    dof = len(jt["joint_names"])
    points = jt["points"]

    def matrix(key: str) -> np.ndarray:
        return np.asarray([p[key] for p in points], dtype=float).reshape(len(points), dof)

    gripper = None
    if jt.get("gripper_joint"):
        gripper = np.asarray(
            [np.nan if p["gripper_position"] is None else p["gripper_position"] for p in points],
            dtype=float,
        )
    return Trajectory(
        agent=jt["agent"],
        group=jt["group"],
        phase=t.get("label", ""),
        holding=t.get("holding"),
        joint_names=list(jt["joint_names"]),
        positions=matrix("positions"),
        velocities=matrix("velocities"),
        time_from_start=np.asarray([p["time_from_start"] for p in points], dtype=float),
        waypoints=np.asarray(jt["waypoints"], dtype=float).reshape(-1, dof),
        velocity_limits=list(jt["velocity_limits"]),
        acceleration_limits=list(jt["acceleration_limits"]),
        gripper_joint=jt.get("gripper_joint"),
        gripper_position=gripper,
    )


def _json_pose(p: Mapping[str, Any]) -> Pose:
    return Pose(np.asarray(p["t"], dtype=float), np.asarray(p["q"], dtype=float))


class Plan:
    """A plan found and validated by :func:`plan`.

    ``steps`` (primitive actions in order, with each GS action's geometric solution and timed
    trajectories), ``tree`` (the decomposition: :class:`TreeNode` by id) and ``root`` (the ids
    of the top tasks), ``stats`` (nodes, backtracks, time; with a scene the GTP tasks'
    statistics), ``plan_text`` (the competition format). :meth:`to_json` gives the plan JSON
    (docs/plan-json.md) that ``htngtp view`` and ``htngtp check`` read."""

    def __init__(self, text: str, domain: PathLike, problem: PathLike, scene: Optional[PathLike]):
        self._text = text
        self._domain = os.fspath(domain)
        self._problem = os.fspath(problem)
        self.scene: Optional[str] = None if scene is None else os.fspath(scene)
        data = json.loads(text)
        self._data = data
        self.domain_name: str = data["domain"]
        self.problem_name: str = data["problem"]
        self.stats: Dict[str, Any] = data["stats"]
        self.root: List[int] = list(data["root"])
        self.tree: Dict[int, TreeNode] = {}
        for n in data["tree"]:
            self.tree[n["id"]] = TreeNode(
                id=n["id"],
                args=list(n["args"]),
                task=n.get("task"),
                method=n.get("method"),
                children=list(n.get("children") or []),
                action=n.get("action"),
                step=n.get("step"),
            )
        self.steps: List[Step] = []
        for s in data["steps"]:
            g = s.get("gtp")
            trajectories = []
            if g:
                trajectories = [t for t in map(_points_trajectory, g["trajectories"]) if t]
            self.steps.append(
                Step(
                    index=s["index"],
                    id=s["id"],
                    action=s["action"],
                    args=list(s["args"]),
                    added=[list(a) for a in s["added"]],
                    deleted=[list(a) for a in s["deleted"]],
                    gtp=None if not g else {k: v for k, v in g.items() if k != "trajectories"},
                    trajectories=trajectories,
                    object_poses={k: _json_pose(v) for k, v in s["object_poses"].items()},
                )
            )

    @property
    def plan_text(self) -> str:
        """The plan in the competition format (``==>``, primitive actions, ``root``, the
        decompositions, ``<==``), as ``htngtp plan`` prints it."""
        return self._data["plan_text"]

    @property
    def trajectories(self) -> List[Trajectory]:
        """Every timed trajectory of the plan, in the order they are played."""
        return [t for s in self.steps for t in s.trajectories]

    def to_json(self) -> str:
        """The plan JSON (docs/plan-json.md) as text, with ``plan_text`` (the competition
        format) added; without a scene, ``scene`` is null and steps have no ``gtp`` part."""
        return self._text

    def write(self, path: PathLike) -> None:
        """Writes :meth:`to_json` to ``path`` (for ``htngtp view`` and ``htngtp check``)."""
        with open(path, "w", encoding="utf-8") as f:
            f.write(self._text)

    def check(self) -> CheckReport:
        """Re-checks the plan independently of the planner. With a scene: ``htngtp check``
        on the plan JSON (collisions over interpolated frames, objects at rest, literals
        re-measured, joint timing within the declared limits, continuity, frames equal to the
        forward kinematics of the points). Without: the HDDL validator on the plan text."""
        if self.scene is None:
            fault = _native.validate_plan_text(self._domain, self._problem, self.plan_text)
            faults = [] if fault is None else [fault]
            return CheckReport(not faults, faults, {"validator": fault or "valid"})
        report = json.loads(_native.check_plan_json(self._text, "<plan>"))
        return CheckReport(not report["faults"], report["faults"], report)

    def __repr__(self) -> str:
        gs = sum(1 for s in self.steps if s.gtp)
        return (
            f"Plan({self.domain_name}/{self.problem_name}: {len(self.steps)} steps, "
            f"{gs} geometric, {len(self.trajectories)} trajectories)"
        )


def plan(
    domain: PathLike,
    problem: PathLike,
    scene: Optional[PathLike] = None,
    strategy: str = "chronological",
    seed: int = 0,
    time_limit: float = 300.0,
    node_limit: Optional[int] = None,
    memory_limit: int = 8192,
    geo_k: int = 3,
    max_acceleration: float = DEFAULT_JOINT_ACCELERATION,
    allow_initial_contact: bool = False,
) -> Plan:
    """Plans ``problem`` of ``domain`` (HDDL files) with the totally-ordered HTN planner, as
    ``htngtp plan``; with ``scene`` the geometric tasks are answered by the GTP in that 3D
    scene and the shared predicates' initial facts come from it. The plan returned has passed
    the validator.

    ``strategy``: ``"symbolic"`` (one geometric solution per task), ``"chronological"`` (every
    choice point, latest first, in rounds that allow more and more revisions of geometric
    solutions that later ones built on), ``"plain-chronological"`` (the same in one search, every solution of the latest
    geometric task first) or ``"geometric-first"`` (on a geometric failure, ``geo_k`` other
    solutions of earlier geometric tasks first, the paper's Fig. 3). The search is
    deterministic for a ``seed``. ``time_limit`` (s) and ``memory_limit`` (MiB of the
    process's resident memory) cover reading the files too; ``node_limit`` bounds the search.
    Calls from several threads run one at a time (the limits of reading are process-wide).

    Raises :class:`ParseError` (with ``file``, ``line``, ``column``) for an invalid HDDL file,
    :class:`SceneError` for an invalid scene, :class:`LimitReached` when a limit stopped the
    search (``limit`` says which), :class:`Unsolvable` when no plan exists, and ValueError for
    a bad argument (or a domain with geometric tasks and no scene).
    """
    text = _native.plan(
        os.fspath(domain),
        os.fspath(problem),
        None if scene is None else os.fspath(scene),
        strategy,
        geo_k,
        seed,
        float(time_limit),
        node_limit,
        memory_limit,
        max_acceleration,
        allow_initial_contact,
    )
    return Plan(text, domain, problem, scene)
