#!/usr/bin/env python3
"""htngtp's geometric benchmarks through Downward Lab: the paper's library experiment
(`htngtp bench library`: scenes nudged, random layouts or random rooms) and GTP tasks alone
(`htngtp gtp`), one Lab run per seed and scene, with success and latency parsed.

  target/labenv/bin/python experiments/geometry.py --seed 1 --runs 100 --fresh --all   # Table II
  target/labenv/bin/python experiments/geometry.py --layout random --seed 1 --runs 100 \\
      --check --fresh --all

Library runs: for each --seed S and index I below --runs N, run I of `htngtp bench library
--runs N --seed S` (`--only I`: the same randomized scene and search seeds as in the full
experiment), per --layout and --strategy. Domain `library-LAYOUT`, problem `seedS-runI`.
GTP runs: each --gtp-task "SCENE TASK ARG..." (default: the paper's tasks in
domains/library/scene.toml) once per --seed. Domain `gtp-TASK`, problem `SCENE-ARGS-seedS`.

Algorithms: htngtp binaries (--binary NAME=PATH) and git revisions (--revision NAME=REV, Lab's
cached revisions), crossed for library runs with the strategies (named BINARY-STRATEGY when
--strategy is given).

Parsed (experiments/run_geometry.py): outcome, coverage, time (run or task latency, s),
solve_time, wall_time; library: plan_length, htn_backtracks, gtp_backtracks, per GTP task
T_latency (s per solution request), T_requests, T_success, and with --check check_clean
(`htngtp check` on the run's plan; the run's time then includes writing the plan JSON); GTP:
points, grasps, orientations, planner_calls, ik_calls, effort_level, failure.

Reports in PATH-eval: report.html (absolute), compare-A-B.html and scatter-A-B.png (time of B
against A) per --compare pair, runs.csv/runs.json, coverage.csv, properties (Lab's JSON).
"""
import argparse
import shlex
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import common  # noqa: E402
from common import ROOT, HERE, fail  # noqa: E402

__doc__ += common.STEPS_HELP

SCENE = ROOT / "domains" / "library" / "scene.toml"
DEFAULT_TASKS = [
    f"{SCENE} pick-and-make-accessible grey-book member",
    f"{SCENE} make-accessible grey-book member",
    f"{SCENE} show grey-book member",
    f"{SCENE} give grey-book member",
    f"{SCENE} put-away pos-machine member",
    f"{SCENE} pick grey-book",
]
STRATEGIES = ["symbolic", "chronological", "geometric-first"]


def seed_list(text):
    a, sep, b = text.partition("-")
    try:
        lo, hi = int(a), int(b) if sep else int(a)
    except ValueError:
        fail(f"--seed {text!r}: expected a number or a range A-B")
    if lo < 0 or hi < lo:
        fail(f"--seed {text!r}: expected 0 <= A <= B")
    return list(range(lo, hi + 1))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=common.help_formatter())
    ap.add_argument("--bench", choices=["library", "gtp", "both"], default="both",
                    help="which runs (default both)")
    ap.add_argument("--seed", action="append", metavar="N|A-B",
                    help="a seed or a range of seeds, A to B (repeatable; default 1)")
    ap.add_argument("--runs", type=int, default=10,
                    help="library runs (scenes) per seed and layout (default 10)")
    ap.add_argument("--layout", action="append", choices=["nudge", "random", "room"],
                    help="library scene variation (repeatable; default nudge)")
    ap.add_argument("--strategy", action="append", choices=STRATEGIES,
                    help="library backtracking strategy (repeatable; default: the bench's own "
                    "per layout, symbolic for nudge and geometric-first for random and room)")
    ap.add_argument("--time-limit", type=int, default=60, help="seconds per library run (default 60)")
    ap.add_argument("--check", action="store_true",
                    help="check each solved library run's plan with `htngtp check`")
    ap.add_argument("--gtp-task", action="append", metavar='"SCENE TASK ARG..."',
                    help="a GTP task to run alone, per seed (repeatable; default: "
                    "pick-and-make-accessible, make-accessible, show, give of grey-book to member, "
                    "put-away of pos-machine, pick of grey-book in domains/library/scene.toml)")
    ap.add_argument("--binary", action="append", metavar="NAME=PATH",
                    help="an htngtp binary (repeatable; default htngtp=target/release/htngtp)")
    ap.add_argument("--revision", action="append", metavar="NAME=REV",
                    help="a git revision of this checkout, built and cached (repeatable)")
    ap.add_argument("--revision-cache", default=str(ROOT / "target" / "lab-revision-cache"),
                    help="where revisions are checked out and built (default target/lab-revision-cache)")
    ap.add_argument("--package-path", action="append", metavar="DIR",
                    help="passed to htngtp (ROS packages of URDF meshes)")
    common.add_common_args(ap, "geometry")
    args = common.parse_args(ap)

    seeds = [n for text in args.seed or ["1"] for n in seed_list(text)]
    if len(set(seeds)) != len(seeds):
        fail("a --seed is given twice")
    if args.runs <= 0 or args.time_limit <= 0:
        fail("--runs and --time-limit must be above 0")
    layouts = args.layout or ["nudge"]
    if len(set(layouts)) != len(layouts) or len(set(args.strategy or [])) != len(args.strategy or []):
        fail("a --layout or --strategy is given twice")
    tasks = []
    for t in args.gtp_task or DEFAULT_TASKS:
        words = shlex.split(t)
        if len(words) < 3:
            fail(f'--gtp-task {t!r}: expected "SCENE TASK ARG..."')
        tasks.append((common.existing_file(words[0], "--gtp-task scene"), words[1], words[2:]))
    binaries = {n: common.executable(p, f"--binary {n}=")
                for n, p in common.named(args.binary, "--binary").items()}
    revisions = common.named(args.revision, "--revision")
    if set(binaries) & set(revisions):
        fail(f"the name(s) {', '.join(sorted(set(binaries) & set(revisions)))} are given twice")
    if not binaries and not revisions:
        binaries = {"htngtp": common.executable(ROOT / "target/release/htngtp",
                                                "the release build (cargo build --release -p htngtp)")}
    extra = [w for p in args.package_path or [] for w in ("--package-path", str(Path(p).resolve()))]
    exp = common.experiment(args, "geometry")
    binaries.update(common.cached_revisions(revisions, args.revision_cache) if revisions else {})
    exp.add_resource("runner", HERE / "run_geometry.py")

    algorithms = []

    def add(algo, domain, problem, cmd, time_limit):
        if algo not in algorithms:
            algorithms.append(algo)
        run = exp.add_run()
        words = [str(w).replace("{", "{{").replace("}", "}}") for w in cmd + extra]
        run.add_command("bench", [sys.executable, "{runner}"] + words,
                        time_limit=time_limit, memory_limit=4096)
        run.set_property("algorithm", algo)
        run.set_property("domain", domain)
        run.set_property("problem", problem)
        run.set_property("id", [algo, domain, problem])

    for bname, binary in binaries.items():
        if args.bench in ("library", "both"):
            for strategy in args.strategy or [None]:
                algo = f"{bname}-{strategy}" if strategy else bname
                for layout in layouts:
                    for seed in seeds:
                        for i in range(args.runs):
                            cmd = ["library", str(binary), "--seed", str(seed), "--runs",
                                   str(args.runs), "--index", str(i), "--layout", layout,
                                   "--time-limit", str(args.time_limit)]
                            if strategy:
                                cmd += ["--strategy", strategy]
                            if args.check:
                                cmd += ["--check"]
                            add(algo, f"library-{layout}", f"seed{seed}-run{i:03d}", cmd,
                                args.time_limit * 2 + 120)
        if args.bench in ("gtp", "both"):
            for scene, task, targs in tasks:
                for seed in seeds:
                    cmd = ["gtp", str(binary), str(scene), task] + targs + ["--seed", str(seed)]
                    add(bname, f"gtp-{task}", f"{scene.stem}-{'-'.join(targs)}-seed{seed}",
                        cmd, 600)

    from lab.reports import Attribute, arithmetic_mean, geometric_mean

    attributes = [
        Attribute("coverage", absolute=True, min_wins=False),
        Attribute("check_clean", absolute=True, min_wins=False),
        Attribute("time", function=geometric_mean),
        Attribute("solve_time", function=geometric_mean),
        Attribute("wall_time", function=geometric_mean),
        Attribute("htn_backtracks", function=arithmetic_mean),
        Attribute("gtp_backtracks", function=arithmetic_mean),
        Attribute("plan_length", function=arithmetic_mean),
        Attribute("*_latency", function=arithmetic_mean),
        Attribute("*_success", absolute=True, min_wins=False),
        Attribute("*_requests", function=sum),
        Attribute("points", function=arithmetic_mean),
        Attribute("grasps", function=arithmetic_mean),
        Attribute("orientations", function=arithmetic_mean),
        Attribute("planner_calls", function=arithmetic_mean),
        Attribute("ik_calls", function=arithmetic_mean),
        "outcome", "failure",
    ]
    columns = ["outcome", "coverage", "time", "wall_time", "plan_length", "htn_backtracks",
               "gtp_backtracks", "check_clean", "pick_and_make_accessible_latency",
               "pick_and_put_away_latency", "points", "grasps", "orientations", "planner_calls",
               "ik_calls", "effort_level", "failure", "exit_code", "message"]
    common.add_steps_and_reports(exp, algorithms, attributes, columns, "time", args.compare)
    exp.run_steps()


if __name__ == "__main__":
    common.run_main(main)
