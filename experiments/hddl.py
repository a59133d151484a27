#!/usr/bin/env python3
"""htngtp on an HDDL suite through Downward Lab: one run per algorithm and problem, the
official verifier on each plan when given, reports per domain.

  target/labenv/bin/python experiments/hddl.py --suite ../shared/benchmarks/ipc2020-total-order \\
      --verifier /tmp/pandaPIparser/pandaPIparser --fresh --all

The suite is an IPC-style folder (one folder per domain; `domain.hddl`, or `P-domain.hddl`
beside problem `P.hddl`) or a list file, one problem a line:
`DOMAIN-NAME DOMAIN-FILE PROBLEM-FILE [SCENE-FILE]` (paths relative to the list; `#` comments;
with a scene, htngtp plans with the GTP in it).

Algorithms: htngtp binaries (`--binary NAME=PATH`; default the release build), git revisions
of this checkout (`--revision NAME=REV`: Lab's cached revisions, built once into
--revision-cache with `cargo build --release -p htngtp`), each crossed with configurations
(`--option NAME="htngtp plan options"`, e.g. `bfs="--best-first-share 1"`), and anchor
planners you installed (`--anchor NAME="COMMAND {domain} {problem}"`; see run_hddl.py --help
for how their plans are read). An algorithm is named BINARY or BINARY-OPTION.

Parsed per run (experiments/run_hddl.py): outcome (solved, unsolvable, limit, no-plan, error),
coverage, unsolvable, limit (which) and limit_time/limit_memory, time, solve_time, wall_time,
memory (peak KiB), nodes, plan_length, validated, and with --verifier the official verdict
(verdict, verified, rejected).

Reports in PATH-eval: report.html (absolute, per domain), compare-A-B.html and scatter-A-B.png
(solve_time of B against A) per --compare pair, runs.csv/runs.json (every run's attributes),
coverage.csv (solved per domain and algorithm), properties (Lab's JSON).
"""
import argparse
import shlex
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import common  # noqa: E402
from common import ROOT, HERE, fail  # noqa: E402

__doc__ += common.STEPS_HELP


def folder_problems(suite, domains, first):
    """(domain name, domain file, problem file, None) of every problem of an IPC-style folder."""
    dirs = sorted(p for p in Path(suite).iterdir() if p.is_dir())
    if not dirs:
        fail(f"--suite {suite}: no domain folders in it")
    for d in dirs:
        if domains and not any(x.lower() in d.name.lower() for x in domains):
            continue
        files = sorted(f for f in d.glob("*.hddl") if "domain" not in f.name.lower())
        for f in files[:first] if first else files:
            own = f.with_name(f.stem + "-domain.hddl")
            dfile = own if own.exists() else d / "domain.hddl"
            if not dfile.exists():
                fail(f"{f}: neither {own.name} nor domain.hddl beside it")
            yield d.name, dfile.resolve(), f.resolve(), None


def list_problems(listfile, domains, first):
    """The problems of a suite list: `DOMAIN-NAME DOMAIN-FILE PROBLEM-FILE [SCENE-FILE]`."""
    base = Path(listfile).resolve().parent
    taken = {}
    for n, line in enumerate(Path(listfile).read_text().splitlines(), 1):
        words = line.split("#", 1)[0].split()
        if not words:
            continue
        if len(words) not in (3, 4):
            fail(f"{listfile}:{n}: expected DOMAIN-NAME DOMAIN-FILE PROBLEM-FILE [SCENE-FILE]")
        name, files = words[0], [base / w for w in words[1:]]
        for f in files:
            if not f.is_file():
                fail(f"{listfile}:{n}: {f} is not a file")
        if domains and not any(x.lower() in name.lower() for x in domains):
            continue
        taken[name] = taken.get(name, 0) + 1
        if first and taken[name] > first:
            continue
        yield (name, files[0].resolve(), files[1].resolve(),
               files[2].resolve() if len(files) == 3 else None)


def lab_literal(word):
    """A command word as Lab passes it on: Lab fills `{name}` with its resources."""
    return str(word).replace("{", "{{").replace("}", "}}")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=common.help_formatter())
    ap.add_argument("--suite", required=True,
                    help="an IPC-style folder (one folder per domain) or a suite list file")
    ap.add_argument("--domain", action="append", help="only domains whose name contains this")
    ap.add_argument("--first", type=int, help="only the first N problems of each domain")
    ap.add_argument("--binary", action="append", metavar="NAME=PATH",
                    help="an htngtp binary (repeatable; default htngtp=target/release/htngtp)")
    ap.add_argument("--revision", action="append", metavar="NAME=REV",
                    help="a git revision of this checkout, built and cached (repeatable)")
    ap.add_argument("--revision-cache", default=str(ROOT / "target" / "lab-revision-cache"),
                    help="where revisions are checked out and built (default target/lab-revision-cache)")
    ap.add_argument("--option", action="append", metavar="NAME=ARGS",
                    help="a configuration: extra `htngtp plan` options, crossed with every "
                    "binary and revision (repeatable)")
    ap.add_argument("--anchor", action="append", metavar="NAME=COMMAND",
                    help="another planner you installed: a command with {domain} and {problem}")
    ap.add_argument("--time-limit", type=int, default=10, help="seconds per run (default 10)")
    ap.add_argument("--memory-limit", type=int, default=2048, help="MiB per run (default 2048)")
    ap.add_argument("--seed", type=int, default=0, help="htngtp's search seed (default 0)")
    ap.add_argument("--verifier", help="pandaPIparser, run as `PATH --verify DOMAIN PROBLEM PLAN`")
    ap.add_argument("--verifier-time-limit", type=int, default=300,
                    help="seconds for the verifier on one plan (default 300)")
    common.add_common_args(ap, "hddl")
    args = common.parse_args(ap)

    if args.time_limit <= 0 or args.memory_limit <= 0:
        fail("--time-limit and --memory-limit must be above 0")
    if args.first is not None and args.first <= 0:
        fail("--first must be above 0")
    suite = Path(args.suite)
    if suite.is_dir():
        problems = list(folder_problems(suite, args.domain, args.first))
    elif suite.is_file():
        problems = list(list_problems(suite, args.domain, args.first))
    else:
        fail(f"--suite {args.suite}: no such folder or file")
    if not problems:
        fail(f"--suite {args.suite}: no problem selected")
    verifier = str(common.executable(args.verifier, "--verifier")) if args.verifier else None

    binaries = {n: common.executable(p, f"--binary {n}=")
                for n, p in common.named(args.binary, "--binary").items()}
    revisions = common.named(args.revision, "--revision")
    anchors = common.named(args.anchor, "--anchor")
    if not binaries and not revisions and not anchors:
        binaries = {"htngtp": common.executable(ROOT / "target/release/htngtp",
                                                "the release build (cargo build --release -p htngtp)")}
    clash = (set(binaries) & set(revisions)) | ((set(binaries) | set(revisions)) & set(anchors))
    if clash:
        fail(f"the algorithm name(s) {', '.join(sorted(clash))} are given twice")
    options = common.named(args.option, "--option", {"": ""})
    for name, extra in options.items():
        try:
            shlex.split(extra)
        except ValueError as e:
            fail(f"--option {name}: {e}")
    exp = common.experiment(args, "hddl")
    binaries.update(common.cached_revisions(revisions, args.revision_cache) if revisions else {})

    exp.add_resource("runner", HERE / "run_hddl.py")
    algorithms = []
    planners = [("htngtp", f"{b}-{o}" if o else b, str(path), shlex.split(extra))
                for b, path in binaries.items() for o, extra in options.items()]
    planners += [("anchor", name, command, []) for name, command in anchors.items()]
    for kind, algo, planner, extra in planners:
        algorithms.append(algo)
        for domain, dfile, pfile, scene in problems:
            run = exp.add_run()
            cmd = [sys.executable, "{runner}", kind, lab_literal(planner), lab_literal(dfile),
                   lab_literal(pfile),
                   "--time-limit", str(args.time_limit), "--memory-limit", str(args.memory_limit),
                   "--seed", str(args.seed), "--verifier-time-limit", str(args.verifier_time_limit)]
            if scene:
                cmd += ["--scene", lab_literal(scene)]
            if verifier:
                cmd += ["--verifier", lab_literal(verifier)]
            if extra:
                cmd += ["--"] + [lab_literal(w) for w in extra]
            # Lab's limits sit above the planner's own (and the verifier's time), so that the
            # planner stops first and says why.
            run.add_command("plan", cmd,
                            time_limit=args.time_limit * 3 + 60 + (args.verifier_time_limit if verifier else 0),
                            memory_limit=args.memory_limit + 1024)
            problem = pfile.name if not scene else f"{pfile.name}@{scene.name}"
            run.set_property("algorithm", algo)
            run.set_property("domain", domain)
            run.set_property("problem", problem)
            run.set_property("id", [algo, domain, problem])
    if len(set(algorithms)) != len(algorithms):
        fail("two algorithms have the same name")

    from lab.reports import Attribute, geometric_mean

    attributes = [
        Attribute("coverage", absolute=True, min_wins=False),
        Attribute("unsolvable", absolute=True, min_wins=False),
        Attribute("limit_time", absolute=True),
        Attribute("limit_memory", absolute=True),
        Attribute("verified", absolute=True, min_wins=False),
        Attribute("rejected", absolute=True),
        Attribute("solve_time", function=geometric_mean),
        Attribute("time", function=geometric_mean),
        Attribute("wall_time", function=geometric_mean),
        Attribute("memory", function=max),
        Attribute("nodes", function=geometric_mean),
        Attribute("plan_length", function=geometric_mean),
        "outcome", "limit", "verdict",
    ]
    columns = ["outcome", "coverage", "unsolvable", "limit", "time", "solve_time", "wall_time",
               "memory", "nodes", "plan_length", "validated", "verdict", "exit_code", "message"]
    common.add_steps_and_reports(exp, algorithms, attributes, columns, "solve_time", args.compare)
    exp.run_steps()


if __name__ == "__main__":
    common.run_main(main)
