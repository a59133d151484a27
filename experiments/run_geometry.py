#!/usr/bin/env python3
"""One Lab run of a geometric benchmark; prints one line `htngtp-result: {...}` for the parser.

    run_geometry.py library BINARY --seed S --runs N --index I --layout nudge|random|room
                    [--strategy X] --time-limit T [--check] [--package-path DIR]
        `htngtp bench library --runs N --only I ...`: run I of the experiment with seed S (its
        own randomized scene), parsed from the bench's JSON. Attributes: outcome
        (solved/failed), coverage, time (s), plan_length, htn_backtracks, gtp_backtracks, per
        GTP task T (dashes as underscores) T_latency (s per solution request), T_requests,
        T_success (1/0); with --check, check_clean (1 when `htngtp check` finds no fault).

    run_geometry.py gtp BINARY SCENE TASK ARG... --seed S [--package-path DIR]
        `htngtp gtp SCENE TASK ARG... --json`: one GTP task alone. Attributes: outcome,
        coverage (1 when it found a solution), time (latency, s), points, grasps, orientations,
        planner_calls, ik_calls, effort_level, failure (the GTP's reason, when it failed).
"""
import argparse
import glob
import json
import subprocess
import sys
import time

PREFIX = "htngtp-result: "


def tail(text):
    return (text.strip().splitlines() or ["no output"])[-1][:500]


def library(a):
    cmd = [a.binary, "bench", "library", "--runs", str(a.runs), "--only", str(a.index),
           "--seed", str(a.seed), "--layout", a.layout, "--time-limit", str(a.time_limit),
           "--out", "bench"]
    if a.strategy:
        cmd += ["--strategy", a.strategy]
    if a.check:
        cmd += ["--plans", "plans"]
    for p in a.package_path or []:
        cmd += ["--package-path", p]
    start = time.monotonic()
    done = subprocess.run(cmd, capture_output=True, text=True, errors="replace")
    r = {"wall_time": round(time.monotonic() - start, 4), "exit_code": done.returncode}
    files = sorted(glob.glob("bench/library-*.json"))
    if done.returncode != 0 or not files:
        r.update(outcome="error", message=tail(done.stderr))
        return r
    with open(files[0]) as f:
        runs = json.load(f)["experiment"]["runs"]
    run = runs[0]
    r.update(outcome="solved" if run.get("solved") else "failed",
             status=run.get("status"), time=run.get("time_s"),
             plan_length=run.get("actions"), htn_backtracks=run.get("htn_backtracks"),
             gtp_backtracks=run.get("gtp_backtracks"), scene_seed=run.get("seed"))
    for task, s in (run.get("tasks") or {}).items():
        key = task.replace("-", "_")
        requests = s.get("attempts") or 0
        r[key + "_requests"] = requests
        r[key + "_success"] = int(bool(s.get("success")))
        if requests:
            r[key + "_latency"] = s.get("time_s", 0) / requests
    if a.check and r["outcome"] == "solved":
        plans = sorted(glob.glob("plans/*.json"))
        if not plans:
            r["check_clean"] = 0
            r["message"] = "solved, but no plan JSON was written"
        else:
            c = subprocess.run([a.binary, "check", plans[0]], capture_output=True, text=True,
                               errors="replace")
            r["check_clean"] = int(c.returncode == 0)
            if c.returncode != 0:
                r["message"] = "htngtp check: " + tail(c.stdout + c.stderr)
    return r


def gtp(a):
    cmd = [a.binary, "gtp", a.scene, a.task] + a.args + ["--json", "--seed", str(a.seed)]
    for p in a.package_path or []:
        cmd += ["--package-path", p]
    start = time.monotonic()
    done = subprocess.run(cmd, capture_output=True, text=True, errors="replace")
    r = {"wall_time": round(time.monotonic() - start, 4), "exit_code": done.returncode}
    try:
        answer = json.loads(done.stdout)
    except json.JSONDecodeError:
        answer = None
    if not isinstance(answer, dict):
        r.update(outcome="error", message=tail(done.stderr))
        return r
    s = answer.get("stats") or {}
    r["outcome"] = "solved" if s.get("success") else "failed"
    r["time"] = s.get("time_s")
    for k in ("points", "grasps", "orientations", "planner_calls", "ik_calls", "effort_level"):
        r[k] = s.get(k)
    if answer.get("failure"):
        r["failure"] = str(answer["failure"])[:300]
    return r


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="kind", required=True)
    lib = sub.add_parser("library")
    lib.add_argument("binary")
    lib.add_argument("--seed", type=int, required=True)
    lib.add_argument("--runs", type=int, required=True)
    lib.add_argument("--index", type=int, required=True)
    lib.add_argument("--layout", choices=["nudge", "random", "room"], default="nudge")
    lib.add_argument("--strategy")
    lib.add_argument("--time-limit", type=int, default=60)
    lib.add_argument("--check", action="store_true")
    lib.add_argument("--package-path", action="append")
    g = sub.add_parser("gtp")
    g.add_argument("binary")
    g.add_argument("scene")
    g.add_argument("task")
    g.add_argument("args", nargs="*")
    g.add_argument("--seed", type=int, required=True)
    g.add_argument("--package-path", action="append")
    a = ap.parse_args(argv)
    r = library(a) if a.kind == "library" else gtp(a)
    r["coverage"] = int(r["outcome"] == "solved")
    if r["coverage"] and r.get("time") is not None:
        r["solve_time"] = r["time"]
    print(PREFIX + json.dumps(r))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
