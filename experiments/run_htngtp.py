#!/usr/bin/env python3
"""One Lab run: `htngtp plan --json` on one HDDL problem, then (optionally) the official
verifier on its plan; prints one line `htngtp-result: {...}` for the parser.

Usage: run_htngtp.py HTNGTP DOMAIN PROBLEM TIME_S MEMORY_MB SEED [VERIFIER] [-- EXTRA...]
"""
import json
import re
import subprocess
import sys


def main(argv):
    extra = []
    if "--" in argv:
        i = argv.index("--")
        argv, extra = argv[:i], argv[i + 1:]
    htngtp, domain, problem, time_s, memory_mb, seed = argv[:6]
    verifier = argv[6] if len(argv) > 6 and argv[6] else None
    cmd = [htngtp, "plan", domain, problem, "--json", "--time-limit", time_s,
           "--memory-limit", memory_mb, "--seed", seed] + extra
    done = subprocess.run(cmd, capture_output=True, text=True)
    result = {"exit_code": done.returncode}
    try:
        answer = json.loads(done.stdout)
    except json.JSONDecodeError:
        answer = {}
        result["error"] = done.stderr.strip().splitlines()[-1:] or ["no output"]
    stats = answer.get("stats") or {}
    result.update(
        status=answer.get("status"),
        limit=answer.get("limit"),
        time_s=stats.get("time_s"),
        nodes=stats.get("nodes"),
        peak_memory_kb=answer.get("peak_memory_kb"),
        validated=answer.get("validated"),
    )
    plan = answer.get("plan_text")
    if plan:
        result["plan_length"] = sum(
            1 for line in plan.splitlines() if re.match(r"^\d+ ", line) and "->" not in line)
        if verifier:
            with open("plan.txt", "w") as f:
                f.write(plan)
            v = subprocess.run([verifier, "--verify", domain, problem, "plan.txt"],
                               capture_output=True, text=True, errors="replace")
            out = re.sub(r"\x1b\[[0-9;]*m", "", v.stdout + v.stderr)
            m = re.search(r"Plan verification result: (\w+)", out)
            result["official"] = m.group(1) if m else "no-verdict"
    print("htngtp-result: " + json.dumps(result))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
