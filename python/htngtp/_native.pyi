"""Type stubs of the native module htngtp._native (use the package ``htngtp`` instead)."""

from typing import Any, Dict, List, Optional, Sequence, Tuple

DEFAULT_JOINT_ACCELERATION: float

class World:
    @staticmethod
    def load(path: str, allow_initial_contact: bool = False) -> World: ...
    def objects(self) -> List[str]: ...
    def movable(self, name: str) -> bool: ...
    def agents(self) -> List[str]: ...
    def agent_kind(self, name: str) -> str: ...
    def object_pose(self, name: str) -> Tuple[List[float], List[float]]: ...
    def agent_pose(self, name: str) -> Tuple[List[float], List[float]]: ...
    def joint_positions(self, name: str) -> List[Tuple[str, float]]: ...
    def holder(self, name: str) -> Optional[Tuple[str, str]]: ...
    def facts_json(self, threshold: float = 0.5, resolution: int = 64) -> str: ...
    def render(
        self,
        view: str,
        path: str,
        width: int = 800,
        height: Optional[int] = None,
        look_at: Optional[str] = None,
    ) -> None: ...

def gtp(
    world: World,
    task: str,
    args: Sequence[str],
    seed: int = 1,
    solutions: int = 1,
    settings: Sequence[Tuple[str, str]] = ...,
    time_limit: Optional[float] = None,
    max_acceleration: float = ...,
) -> Dict[str, Any]: ...
def gtp_rust_seconds(
    world: World,
    task: str,
    args: Sequence[str],
    seed: int = 1,
    solutions: int = 1,
    settings: Sequence[Tuple[str, str]] = ...,
) -> Tuple[float, int]: ...
def plan(
    domain: str,
    problem: str,
    scene: Optional[str] = None,
    strategy: str = "chronological",
    geo_k: int = 3,
    seed: int = 0,
    time_limit: float = 300.0,
    node_limit: Optional[int] = None,
    memory_limit: int = 8192,
    max_acceleration: float = ...,
    allow_initial_contact: bool = False,
) -> str: ...
def check_plan_json(text: str, file: str = "<plan>") -> str: ...
def validate_plan_text(domain: str, problem: str, text: str) -> Optional[str]: ...
