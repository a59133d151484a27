#!/usr/bin/env python3
"""One Lab run of an HDDL problem: htngtp (`htngtp plan --json`) or an anchor planner (any
command), then, when given, the official verifier (pandaPIparser) on the plan. Prints one line
`htngtp-result: {...}` that experiments/common.py's parser turns into the run's properties:

  outcome        solved | unsolvable | limit | no-plan | error
  coverage       1 when solved;  unsolvable: 1 when proven unsolvable
  limit          which limit stopped it (time, memory, nodes, ...; htngtp's own word), or null
  limit_time, limit_memory   1 when that limit stopped it
  time           the planner's own time (s; htngtp's statistics), wall_time: measured here (s)
  solve_time     time of solved runs only (for scatter plots)
  memory         peak resident memory of the planner (KiB; the larger of htngtp's own report
                 and the operating system's maximum resident set of the child)
  nodes, plan_length (primitive actions), validated (htngtp's own validator)
  verdict        the official verifier's word: true | false | no-verdict | timeout
  verified, rejected   1 when the verdict is true / false

    run_hddl.py htngtp BINARY DOMAIN PROBLEM --time-limit S --memory-limit MIB [--seed N]
                [--scene SCENE] [--verifier PATH] [-- EXTRA htngtp plan OPTIONS...]
    run_hddl.py anchor 'COMMAND {domain} {problem}' DOMAIN PROBLEM --time-limit S ...

An anchor's command is split like a shell line; {domain}, {problem} and {plan} are replaced by
the files' paths; its plan is read from the file {plan} when the command names it, otherwise
from its output, from the line `==>` to the line `<==` (the IPC format).
"""
import argparse
import json
import re
import resource
import shlex
import subprocess
import sys
import time

PREFIX = "htngtp-result: "


def plan_length(text):
    return sum(1 for line in text.splitlines()
               if re.match(r"^\d+ ", line) and "->" not in line)


def ipc_plan(output):
    """The IPC-format plan in a planner's output: from `==>` to `<==`, or None."""
    lines = output.splitlines()
    try:
        start = next(i for i, l in enumerate(lines) if l.strip() == "==>")
    except StopIteration:
        return None
    end = next((i for i in range(start, len(lines)) if lines[i].strip() == "<=="), len(lines) - 1)
    return "\n".join(lines[start:end + 1]) + "\n"


def verify(verifier, domain, problem, plan_text, time_limit):
    with open("plan.txt", "w") as f:
        f.write(plan_text)
    try:
        v = subprocess.run([verifier, "--verify", domain, problem, "plan.txt"],
                           capture_output=True, text=True, errors="replace", timeout=time_limit)
    except subprocess.TimeoutExpired:
        return "timeout"
    out = re.sub(r"\x1b\[[0-9;]*m", "", v.stdout + v.stderr)
    m = re.search(r"Plan verification result: (\w+)", out)
    return m.group(1).lower() if m else "no-verdict"


def limit_memory(mib):
    def set_limit():
        b = mib * 1024 * 1024
        resource.setrlimit(resource.RLIMIT_AS, (b, b))
    return set_limit


def run(cmd, time_limit, memory_mib, own_memory_limit):
    """Runs the planner: (CompletedProcess or None when killed at the time limit, wall s,
    peak KiB). With `own_memory_limit` false the address space is capped here."""
    start = time.monotonic()
    try:
        done = subprocess.run(cmd, capture_output=True, text=True, errors="replace",
                              timeout=time_limit,
                              preexec_fn=None if own_memory_limit else limit_memory(memory_mib))
    except subprocess.TimeoutExpired:
        done = None
    wall = time.monotonic() - start
    return done, wall, resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss


def htngtp(a, extra):
    cmd = [a.planner, "plan", a.domain, a.problem, "--json", "--time-limit", str(a.time_limit),
           "--memory-limit", str(a.memory_limit), "--seed", str(a.seed)]
    if a.scene:
        cmd += ["--scene", a.scene]
    cmd += extra
    # htngtp stops itself at its limits and says which; the backstop here is for a hang.
    done, wall, peak = run(cmd, a.time_limit * 2 + 30, a.memory_limit, True)
    r = {"wall_time": round(wall, 4), "memory": peak}
    if done is None:
        r.update(outcome="limit", limit="time", exit_code=None)
        return r, None
    r["exit_code"] = done.returncode
    try:
        answer = json.loads(done.stdout)
    except json.JSONDecodeError:
        answer = None
    if not isinstance(answer, dict):
        r["outcome"] = "error"
        r["message"] = (done.stderr.strip().splitlines() or ["no output"])[-1][:500]
        return r, None
    status = answer.get("status")
    stats = answer.get("stats") or {}
    r["outcome"] = {"found": "solved", "solved": "solved", "unsolvable": "unsolvable",
                    "limit-reached": "limit", "limit": "limit"}.get(status, "error")
    if r["outcome"] == "limit":
        r["limit"] = answer.get("limit") or "other"
    if r["outcome"] == "error":
        r["message"] = f"status {status!r}"
    t = stats.get("time_s")
    if t is None and stats.get("time_ms") is not None:
        t = stats["time_ms"] / 1000
    r["time"] = t
    r["nodes"] = stats.get("nodes")
    r["htn_backtracks"] = stats.get("htn_backtracks")
    r["geo_backtracks"] = stats.get("geo_backtracks", stats.get("gtp_backtracks"))
    own = answer.get("peak_memory_kb")
    if own:
        r["memory"] = max(own, peak)
    if "validated" in answer:
        r["validated"] = int(bool(answer["validated"]))
    plan = None
    if r["outcome"] == "solved":
        plan = answer.get("plan_text")
        if plan:
            r["plan_length"] = plan_length(plan)
        elif isinstance(answer.get("steps"), list):      # with a scene: the plan JSON
            r["plan_length"] = len(answer["steps"])
    return r, plan


def anchor(a, _extra):
    words = [w.replace("{domain}", a.domain).replace("{problem}", a.problem)
             .replace("{plan}", "anchor-plan.txt") for w in shlex.split(a.planner)]
    done, wall, peak = run(words, a.time_limit, a.memory_limit, False)
    r = {"wall_time": round(wall, 4), "time": round(wall, 4), "memory": peak}
    if done is None:
        r.update(outcome="limit", limit="time", exit_code=None)
        return r, None
    r["exit_code"] = done.returncode
    plan = None
    if "{plan}" in a.planner:
        try:
            with open("anchor-plan.txt") as f:
                plan = ipc_plan(f.read()) or None
        except OSError:
            plan = None
    else:
        plan = ipc_plan(done.stdout)
    if plan:
        r["outcome"] = "solved"
        r["plan_length"] = plan_length(plan)
    elif "MemoryError" in done.stderr or "bad_alloc" in done.stderr:
        r.update(outcome="limit", limit="memory")
    else:
        r["outcome"] = "no-plan"
    return r, plan


def main(argv):
    extra = []
    if "--" in argv:
        i = argv.index("--")
        argv, extra = argv[:i], argv[i + 1:]
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("kind", choices=["htngtp", "anchor"])
    ap.add_argument("planner", help="htngtp's binary, or the anchor's command line")
    ap.add_argument("domain")
    ap.add_argument("problem")
    ap.add_argument("--time-limit", type=int, required=True, help="seconds")
    ap.add_argument("--memory-limit", type=int, required=True, help="MiB")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--scene")
    ap.add_argument("--verifier")
    ap.add_argument("--verifier-time-limit", type=int, default=300)
    a = ap.parse_args(argv)
    r, plan = (htngtp if a.kind == "htngtp" else anchor)(a, extra)
    r["coverage"] = int(r["outcome"] == "solved")
    r["unsolvable"] = int(r["outcome"] == "unsolvable")
    r["limit_time"] = int(r.get("limit") == "time")
    r["limit_memory"] = int(r.get("limit") == "memory")
    r.setdefault("limit", None)
    if r["coverage"] and r.get("time") is not None:
        r["solve_time"] = r["time"]
    if a.verifier and plan:
        r["verdict"] = verify(a.verifier, a.domain, a.problem, plan, a.verifier_time_limit)
        r["verified"] = int(r["verdict"] == "true")
        r["rejected"] = int(r["verdict"] == "false")
    print(PREFIX + json.dumps(r))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
