"""Overhead of the Python layer on a GTP call: the library experiment's requests (show, give,
make-accessible of a book to the member, in the library scene) through `htngtp.gtp` versus the
same call entirely in Rust (`htngtp._native.gtp_rust_seconds`: the same planner, stream, and
trajectory timing, timed inside Rust with no Python object made). Each seed runs both ways,
alternating which goes first; the report gives per request the median seconds of each and
their ratio (the target is within 10 %, a ratio of at most 1.10).

    python python/bench/overhead.py [--repeats 10] [--solutions 1]
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

import htngtp
from htngtp import _native

SCENE = Path(__file__).resolve().parents[2] / "domains" / "library" / "scene.toml"
REQUESTS = [
    ("show", ["grey-book", "member"]),
    ("give", ["grey-book", "member"]),
    ("make-accessible", ["grey-book", "member"]),
]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=10, help="seeds per request")
    parser.add_argument("--solutions", type=int, default=1, help="solutions per call")
    args = parser.parse_args()
    world = htngtp.World.load(SCENE)
    # Warm the planner's per-scene cache (robot set-up, grasps) once, as a session would.
    htngtp.gtp(world, "pick", ["grey-book"], seed=0)
    print(f"{'request':<34} {'python s':>9} {'rust s':>9} {'ratio':>6}")
    worst = 0.0
    for task, names in REQUESTS:
        py_times, rust_times = [], []
        for seed in range(1, args.repeats + 1):
            order = [0, 1] if seed % 2 else [1, 0]
            for which in order:
                if which == 0:
                    began = time.perf_counter()
                    try:
                        htngtp.gtp(world, task, names, seed=seed, solutions=args.solutions)
                    except htngtp.HtngtpError:
                        pass  # no solution for this seed: the same work was done either way
                    py_times.append(time.perf_counter() - began)
                else:
                    seconds, _ = _native.gtp_rust_seconds(
                        world._native, task, names, seed, args.solutions
                    )
                    rust_times.append(seconds)
        py, rust = statistics.median(py_times), statistics.median(rust_times)
        ratio = py / rust if rust > 0 else float("inf")
        worst = max(worst, ratio)
        label = f"{task}({', '.join(names)})"
        print(f"{label:<34} {py:>9.4f} {rust:>9.4f} {ratio:>6.3f}")
    verdict = "within" if worst <= 1.10 else "NOT within"
    print(f"largest ratio {worst:.3f}: {verdict} the 10 % target")


if __name__ == "__main__":
    main()
