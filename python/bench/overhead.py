"""Overhead of the Python layer on a GTP call: the library experiment's requests (show, give,
make-accessible of a book to the member, in the library scene) through `htngtp.gtp` versus the
same call entirely in Rust (`htngtp._native.gtp_rust_seconds`: the same planner, stream and
trajectory timing, with no Python object made). Each seed runs both ways, alternating which
goes first. Per request the report gives the median wall-clock seconds of each (the Rust call
timed inside Rust) and the median CPU seconds of the process (all threads, `process_time`,
which a busy machine disturbs less than the wall clock), and their ratios; the target is a
Python call within 10 % of the Rust one (ratio at most 1.10).

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
    print(
        f"{'request':<34} {'py wall':>8} {'rust wall':>9} {'ratio':>6}"
        f" {'py cpu':>8} {'rust cpu':>8} {'ratio':>6}"
    )
    worst = 0.0
    for task, names in REQUESTS:
        wall: dict = {0: [], 1: []}
        cpu: dict = {0: [], 1: []}
        for seed in range(1, args.repeats + 1):
            for which in ([0, 1] if seed % 2 else [1, 0]):
                began, began_cpu = time.perf_counter(), time.process_time()
                if which == 0:
                    try:
                        htngtp.gtp(world, task, names, seed=seed, solutions=args.solutions)
                    except htngtp.HtngtpError:
                        pass  # no solution for this seed: the same work was done either way
                    wall[0].append(time.perf_counter() - began)
                else:
                    seconds, _ = _native.gtp_rust_seconds(
                        world._native, task, names, seed, args.solutions
                    )
                    wall[1].append(seconds)
                cpu[which].append(time.process_time() - began_cpu)
        w = [statistics.median(wall[k]) for k in (0, 1)]
        c = [statistics.median(cpu[k]) for k in (0, 1)]
        wr, cr = w[0] / w[1], c[0] / c[1]
        worst = max(worst, cr)
        label = f"{task}({', '.join(names)})"
        print(f"{label:<34} {w[0]:>8.4f} {w[1]:>9.4f} {wr:>6.3f} {c[0]:>8.4f} {c[1]:>8.4f} {cr:>6.3f}")
    # The part of the Python layer that a busy machine's noise hides: turning one native
    # answer (numpy arrays already made in Rust) into the package's objects.
    raw = _native.gtp(world._native, "make-accessible", ["grey-book", "member"], 1, 1)
    reps = 200
    began = time.process_time()
    for _ in range(reps):
        htngtp._gtp_result("make-accessible", ["grey-book", "member"], raw)
    ms = (time.process_time() - began) / reps * 1e3
    print(f"Python-side conversion of one make-accessible answer: {ms:.3f} ms of CPU")
    verdict = "within" if worst <= 1.10 else "NOT within"
    print(f"largest CPU ratio {worst:.3f}: {verdict} the 10 % target")


if __name__ == "__main__":
    main()
