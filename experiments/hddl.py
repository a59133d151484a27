#!/usr/bin/env python3
"""htngtp on an IPC-style HDDL suite through Downward Lab: one run per (algorithm, problem),
the official verifier on each plan when given, a report of coverage, time, memory and
verdicts per domain (HTML), and the parsed properties (JSON).

    python experiments/hddl.py --suite ../shared/benchmarks/ipc2020-total-order \\
        --verifier /tmp/pandaPIparser/pandaPIparser --all          # build, run, fetch, report

Algorithms are binaries (`--binary NAME=PATH`, repeatable; default the release build) and
options for them (`--option NAME=ARGS`, repeatable, e.g. `chrono="--seed 1"`). Runs go on all
cores of this machine, or on a Slurm grid with `--slurm PARTITION` (with `--slurm-memory`,
`--slurm-time`). Lab's own step arguments work as well (`1 2 3`, `--all`, `build`...).
"""
import argparse
import json
import os
import shlex
import sys
from pathlib import Path

from lab.environments import LocalEnvironment, SlurmEnvironment
from lab.experiment import Experiment
from lab.parser import Parser
from lab.reports import Attribute, geometric_mean
from downward.reports.absolute import AbsoluteReport

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent


def problems(suite, domains, first):
    """(domain name, domain file, problem file) of every problem of the suite, by the
    benchmarks' conventions (`domain.hddl`, or `X-domain.hddl` beside `X.hddl`)."""
    for d in sorted(p for p in Path(suite).iterdir() if p.is_dir()):
        if domains and not any(x.lower() in d.name.lower() for x in domains):
            continue
        files = sorted(f for f in d.glob("*.hddl") if "domain" not in f.name)
        for f in files[:first] if first else files:
            own = f.with_name(f.stem + "-domain.hddl")
            yield d.name, (own if own.exists() else d / "domain.hddl"), f


def parse_result(content, props):
    for line in content.splitlines():
        if line.startswith("htngtp-result: "):
            r = json.loads(line[len("htngtp-result: "):])
            props["status"] = r.get("status")
            props["limit"] = r.get("limit")
            props["coverage"] = int(r.get("status") == "found")
            props["unsolvable"] = int(r.get("status") == "unsolvable")
            for k in ("time_s", "nodes", "peak_memory_kb", "plan_length", "exit_code"):
                if r.get(k) is not None:
                    props[k] = r[k]
            if "official" in r:
                props["official"] = r["official"]
                props["accepted"] = int(r["official"] == "true")
                props["rejected"] = int(r["official"] == "false")
            if r.get("status") == "found" and r.get("time_s") is not None:
                props["solve_time"] = r["time_s"]


def named(pairs, default):
    out = {}
    for p in pairs or []:
        name, _, value = p.partition("=")
        out[name] = value
    return out or default


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--suite", required=True, help="an IPC-style folder: one folder per domain")
    ap.add_argument("--domain", action="append", help="only domains whose name contains this")
    ap.add_argument("--first", type=int, help="only the first N problems of each domain")
    ap.add_argument("--binary", action="append", help="NAME=PATH of an htngtp binary (repeatable)")
    ap.add_argument("--option", action="append", help="NAME=ARGS: extra `plan` options (repeatable)")
    ap.add_argument("--time-limit", type=int, default=10, help="seconds per run (htngtp's and Lab's)")
    ap.add_argument("--memory-limit", type=int, default=2048, help="MiB per run")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--verifier", help="pandaPIparser, run as `PATH --verify DOMAIN PROBLEM PLAN`")
    ap.add_argument("--processes", type=int, help="local runs at once (default: all cores)")
    ap.add_argument("--slurm", metavar="PARTITION", help="run on a Slurm grid in this partition")
    ap.add_argument("--slurm-memory", default="3G", help="memory per Slurm task")
    ap.add_argument("--slurm-time", default="0", help="time per Slurm task (Slurm's format)")
    ap.add_argument("--path", help="experiment folder (default: experiments/data/hddl)")
    args, lab_args = ap.parse_known_args()
    sys.argv = [sys.argv[0]] + lab_args

    env = (SlurmEnvironment(partition=args.slurm, memory_per_cpu=args.slurm_memory,
                            time_limit_per_task=args.slurm_time)
           if args.slurm else LocalEnvironment(processes=args.processes))
    path = args.path or str(HERE / "data" / "hddl")
    exp = Experiment(path=path, environment=env)
    binaries = named(args.binary, {"htngtp": str(ROOT / "target/release/htngtp")})
    options = named(args.option, {"": ""})
    exp.add_resource("runner", HERE / "run_htngtp.py")
    for bname, bpath in binaries.items():
        bpath = os.path.abspath(bpath)
        for oname, extra in options.items():
            algo = "-".join(x for x in (bname, oname) if x)
            for domain, dfile, pfile in problems(args.suite, args.domain, args.first):
                run = exp.add_run()
                cmd = [sys.executable, "{runner}", bpath, str(dfile.resolve()), str(pfile.resolve()),
                       str(args.time_limit), str(args.memory_limit), str(args.seed),
                       os.path.abspath(args.verifier) if args.verifier else ""]
                if extra:
                    cmd += ["--"] + shlex.split(extra)
                # Lab's limits sit above htngtp's own, so that htngtp stops first and says why.
                run.add_command("plan", cmd, time_limit=args.time_limit * 3 + 600,
                                memory_limit=args.memory_limit + 1024)
                run.set_property("algorithm", algo)
                run.set_property("domain", domain)
                run.set_property("problem", pfile.name)
                run.set_property("id", [algo, domain, pfile.name])
    parser = Parser()
    parser.add_function(parse_result, file="run.log")
    exp.add_parser(parser)
    exp.add_step("build", exp.build)
    exp.add_step("start", exp.start_runs)
    exp.add_step("parse", exp.parse)
    exp.add_fetcher(name="fetch")
    attributes = [
        Attribute("coverage", absolute=True, min_wins=False),
        Attribute("unsolvable", absolute=True, min_wins=False),
        Attribute("accepted", absolute=True, min_wins=False),
        Attribute("rejected", absolute=True),
        Attribute("solve_time", function=geometric_mean),
        Attribute("peak_memory_kb", function=max),
        "nodes", "plan_length", "limit", "official",
    ]
    exp.add_report(AbsoluteReport(attributes=attributes), outfile="report.html")
    exp.run_steps()


if __name__ == "__main__":
    main()
