"""The exceptions of htngtp: every failure of a call is one of these (or ValueError for a bad
argument), never an exit code."""

from __future__ import annotations

import json
from typing import Any, Dict, Optional


class HtngtpError(Exception):
    """The base of htngtp's own exceptions."""


class ParseError(HtngtpError, ValueError):
    """An HDDL file is invalid: ``file``, ``line`` and ``column`` say where (1-based; ``line``
    and ``column`` are 0 when the error concerns the file as a whole, e.g. it cannot be read),
    ``message`` what is wrong (``str(e)`` is ``FILE:LINE:COL: message``)."""

    def __init__(self, message: str, file: str, line: int, column: int) -> None:
        super().__init__(message)
        self.message = message
        self.file = file
        self.line = line
        self.column = column


class SceneError(HtngtpError, ValueError):
    """A scene file is invalid (the message names the file and the key path), or it starts in
    collision."""


def _stats(text: Optional[str]) -> Dict[str, Any]:
    if not text:
        return {}
    value = json.loads(text)
    return value if isinstance(value, dict) else {}


class LimitReached(HtngtpError):
    """The search stopped incomplete: ``limit`` is ``"time"``, ``"nodes"``, ``"memory"`` or
    ``"geometric-alternatives"`` (the symbolic strategy's cap on geometric solutions: not a proof that
    no plan exists); ``stats`` are the search's statistics so far (empty when it stopped before
    searching)."""

    def __init__(self, message: str, limit: str, stats: Optional[str] = None) -> None:
        super().__init__(message)
        self.message = message
        self.limit = limit
        self.stats: Dict[str, Any] = _stats(stats)


class Unsolvable(HtngtpError):
    """No plan (or no geometric solution) exists: the whole search space was explored with no
    cap. The message names the last geometric task that failed and why, when there is one;
    ``stats`` are the search's statistics."""

    def __init__(self, message: str, stats: Optional[str] = None) -> None:
        super().__init__(message)
        self.message = message
        self.stats: Dict[str, Any] = _stats(stats)


__all__ = ["HtngtpError", "ParseError", "SceneError", "LimitReached", "Unsolvable"]
