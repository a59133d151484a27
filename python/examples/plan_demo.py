"""Plans the demo (the paper's Fig. 4 library scenario, as `htngtp demo`) from Python, prints
the plan and its geometric steps, re-checks it, and plots one arm's joint positions over time
with matplotlib when it is installed (else says so).

    python python/examples/plan_demo.py [--out arm.png]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

import htngtp

LIBRARY = Path(__file__).resolve().parents[2] / "domains" / "library"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="plan_demo_arm.png", help="where to save the plot")
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args()

    plan = htngtp.plan(
        LIBRARY / "domain-compound.hddl",
        LIBRARY / "fig4.hddl",
        scene=LIBRARY / "scene.toml",
        strategy="geometric-first",
        seed=args.seed,
    )
    print(plan)
    for step in plan.steps:
        line = f"{step.index:>2}. {step.action} {' '.join(step.args)}"
        if step.gtp:
            line += f"   [GTP {step.gtp['task']}: {len(step.trajectories)} trajectories]"
        print(line)
    print("stats:", {k: v for k, v in plan.stats.items() if k != "gtp_tasks"})
    report = plan.check()
    print("independent check:", "clean" if report.clean else f"{len(report.faults)} faults")

    # One arm's joints over the whole plan: its trajectories one after the other in time.
    arm = next(t.group for t in plan.trajectories if t.group.endswith("arm"))
    pieces = [t for t in plan.trajectories if t.group == arm]
    names = pieces[0].joint_names
    times, positions, start = [], [], 0.0
    for t in pieces:
        times.append(start + t.time_from_start)
        positions.append(t.positions)
        start += t.duration
    time = np.concatenate(times)
    q = np.concatenate(positions)
    print(f"{arm}: {len(pieces)} trajectories, {len(time)} points, {start:.1f} s of motion")
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib is not installed: no plot (pip install matplotlib)")
        return
    fig, ax = plt.subplots(figsize=(10, 5))
    for j, name in enumerate(names):
        ax.plot(time, q[:, j], label=name)
    ax.set_xlabel("time in motion (s)")
    ax.set_ylabel("joint position (rad or m)")
    ax.set_title(f"{arm} over the demo's plan")
    ax.legend(fontsize="small", ncol=2)
    fig.tight_layout()
    fig.savefig(args.out, dpi=100)
    print("plot written to", args.out)


if __name__ == "__main__":
    main()
