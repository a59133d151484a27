"""What the Lab experiments of this folder share: the environment (local on all cores, or a
Slurm grid), the experiment folder, the steps, and the reports (Lab's absolute and comparative
reports in HTML, a scatter plot of one attribute between two algorithms, and every run's
attributes as CSV and JSON, with coverage per domain)."""
import argparse
import csv
import json
import os
import shlex
import shutil
import subprocess
import sys
from collections import defaultdict
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
RESULT_PREFIX = "htngtp-result: "

STEPS_HELP = """
Lab's step arguments follow the options: `--all` runs every step; or name steps, in order:
build (writes the run folders), start (runs them), parse, fetch (collects the properties into
the -eval folder), then the reports (report, compare, scatter, tables). With no step and no
--all, Lab lists the steps.
"""


class UsageError(Exception):
    """Bad input to one of the experiment scripts: printed as `error: ...`, exit 2."""


def fail(message):
    raise UsageError(message)


def run_main(main):
    """Run `main()`, turning a UsageError into a one-line message and exit code 2."""
    try:
        main()
    except UsageError as e:
        print(f"error: {e}", file=sys.stderr)
        sys.exit(2)


def existing_file(path, what):
    p = Path(path)
    if not p.is_file():
        fail(f"{what} {path!r} is not a file")
    return p.resolve()


def executable(path, what):
    p = existing_file(path, what)
    if not os.access(p, os.X_OK):
        fail(f"{what} {path!r} is not executable")
    return p


def named(pairs, what, default=None):
    """`NAME=VALUE` arguments as an ordered dict; a name may appear once."""
    out = {}
    for p in pairs or []:
        name, sep, value = p.partition("=")
        if not sep or not name:
            fail(f"{what} {p!r}: expected NAME=VALUE")
        if not all(c.isalnum() or c in "-_." for c in name):
            fail(f"{what} {p!r}: the name may hold letters, digits, '-', '_' and '.' only")
        if name in out:
            fail(f"{what}: the name {name!r} is given twice")
        out[name] = value
    return out or dict(default or {})


def add_common_args(ap, default_name):
    g = ap.add_argument_group("where and how the runs go")
    g.add_argument("--path", help=f"experiment folder (default: experiments/data/{default_name}); "
                   "the properties and reports go to PATH-eval")
    g.add_argument("--fresh", action="store_true",
                   help="remove the experiment folder and its -eval folder first, without asking")
    g.add_argument("--processes", type=int,
                   help="local runs at once (default: all cores of this machine)")
    g.add_argument("--slurm", metavar="PARTITION",
                   help="send the runs to a Slurm grid, in this partition (sbatch on PATH; the "
                   "checkout, the binaries and this Python must be on a shared file system)")
    g.add_argument("--slurm-memory", default="3G", metavar="MEM",
                   help="memory per Slurm task, Slurm's format (default 3G)")
    g.add_argument("--slurm-time", default="0", metavar="TIME",
                   help="wall time per Slurm task, Slurm's format, e.g. 2:00:00 (default 0: no limit)")
    g.add_argument("--slurm-qos", help="Slurm quality of service (default: the partition's)")
    g.add_argument("--slurm-max-tasks", type=int, default=1000,
                   help="most array tasks per job; runs are grouped to fit (default 1000)")
    g.add_argument("--slurm-setup", default="",
                   help="shell lines run before each Slurm job, e.g. `module load python`")
    r = ap.add_argument_group("reports")
    r.add_argument("--compare", nargs=2, metavar=("ALGO1", "ALGO2"), action="append",
                   help="a comparative report and a scatter plot of ALGO2 against ALGO1 "
                   "(repeatable; default: the first two algorithms, when there are two or more)")
    return ap


def parse_args(ap):
    """Our options, then Lab's step arguments left in sys.argv for Lab's own parser."""
    argv = sys.argv[1:]
    args, rest = ap.parse_known_args(argv)
    unknown = [a for a in rest if a.startswith("-") and a != "--all"]
    if unknown:
        ap.error(f"unknown option(s): {' '.join(unknown)}")
    if rest and argv[len(argv) - len(rest):] != rest:
        ap.error(f"give Lab's steps ({' '.join(rest)}) after every option")
    # What a Slurm job of a later step runs this script with (--fresh would remove the runs).
    args.replay = [a for a in argv[:len(argv) - len(rest)] if a != "--fresh"]
    sys.argv = [sys.argv[0]] + rest
    if args.processes is not None and not 1 <= args.processes <= os.cpu_count():
        fail(f"--processes {args.processes}: this machine has {os.cpu_count()} cores")
    return args


def environment(args):
    from lab import tools
    from lab.environments import LocalEnvironment, SlurmEnvironment

    if not args.slurm:
        return LocalEnvironment(processes=args.processes)

    class Slurm(SlurmEnvironment):
        """A generic Slurm grid (Lab's SlurmEnvironment names neither a task cap nor a QOS)."""
        MAX_TASKS = args.slurm_max_tasks

        def _get_job_header(self, step, is_last):
            header = super()._get_job_header(step, is_last)
            if self.qos is None:
                header = "\n".join(l for l in header.splitlines()
                                   if not l.startswith("#SBATCH --qos=")) + "\n"
            return header

        def _get_step_job_body(self, step):
            # Lab's own body runs `python SCRIPT STEP`: this script needs its options too.
            words = [tools.get_python_executable(), os.path.abspath(sys.argv[0])] + args.replay
            return (f"cd {shlex.quote(os.getcwd())}\n"
                    + " ".join(shlex.quote(str(w)) for w in words + [step.name]) + "\n")

    if shutil.which("sbatch") is None:
        print("warning: sbatch is not on PATH here; the start step will fail", file=sys.stderr)
    return Slurm(partition=args.slurm, qos=args.slurm_qos, memory_per_cpu=args.slurm_memory,
                 time_limit_per_task=args.slurm_time, setup=args.slurm_setup)


def experiment(args, default_name):
    from lab.experiment import Experiment

    path = Path(args.path).resolve() if args.path else HERE / "data" / default_name
    if args.fresh:
        for p in (path, Path(str(path) + "-eval"), Path(str(path) + "-grid-steps")):
            if p.exists():
                shutil.rmtree(p)
    return Experiment(path=str(path), environment=environment(args))


def result_parser():
    """Lab's parser of the runners' one line `htngtp-result: {...}`: every key becomes a
    property of the run."""
    from lab.parser import Parser

    def parse(content, props):
        found = False
        for line in content.splitlines():
            if line.startswith(RESULT_PREFIX):
                props.update(json.loads(line[len(RESULT_PREFIX):]))
                found = True
        props["result_line"] = int(found)
        if not found:
            props.add_unexplained_error("the runner printed no htngtp-result line")

    p = Parser()
    p.add_function(parse, file="run.log")
    return p


def add_steps_and_reports(exp, algorithms, attributes, csv_columns, scatter_attribute, compare):
    """The steps build, start, parse, fetch and the reports: report.html (absolute, per domain),
    compare-A-B.html and scatter-A-B.png per pair, runs.csv, runs.json and coverage.csv."""
    from downward.reports.absolute import AbsoluteReport
    from downward.reports.compare import ComparativeReport
    from downward.reports.scatter import ScatterPlotReport

    for pair in compare or []:
        for a in pair:
            if a not in algorithms:
                fail(f"--compare {' '.join(pair)}: no algorithm {a!r} (there are: "
                     f"{', '.join(algorithms)})")
    pairs = [tuple(p) for p in compare] if compare else (
        [(algorithms[0], algorithms[1])] if len(algorithms) >= 2 else [])

    exp.add_parser(result_parser())
    exp.add_step("build", exp.build)
    exp.add_step("start", exp.start_runs)
    exp.add_step("parse", exp.parse)
    exp.add_fetcher(name="fetch", merge=False)
    exp.add_report(AbsoluteReport(attributes=attributes, filter_algorithm=algorithms),
                   name="report", outfile="report.html")
    for a, b in pairs:
        exp.add_report(ComparativeReport([(a, b)], attributes=attributes),
                       name=f"compare-{a}-{b}", outfile=f"compare-{a}-{b}.html")
        exp.add_report(ScatterPlotReport(attributes=[scatter_attribute], filter_algorithm=[a, b],
                                         format="png", show_missing=True,
                                         get_category=lambda r1, r2: r1["domain"]),
                       name=f"scatter-{a}-{b}", outfile=f"scatter-{a}-{b}.png")
    exp.add_step("tables", write_tables, exp.eval_dir, csv_columns)


def load_properties(eval_dir):
    path = Path(eval_dir) / "properties"
    if not path.is_file():
        fail(f"{path} is missing: run the fetch step first")
    return json.loads(path.read_text())


def coverage_rows(props):
    """(domain, algorithm, runs, solved) per domain and algorithm, sorted."""
    table = defaultdict(lambda: [0, 0])
    for run in props.values():
        key = (run.get("domain"), run.get("algorithm"))
        table[key][0] += 1
        table[key][1] += int(run.get("coverage") or 0)
    return [(d, a, n, s) for (d, a), (n, s) in sorted(table.items())]


def write_tables(eval_dir, columns):
    """runs.csv (one row per run: algorithm, domain, problem, then `columns`), runs.json (the
    same rows), coverage.csv (runs and solved per domain and algorithm)."""
    props = load_properties(eval_dir)
    head = ["algorithm", "domain", "problem"] + [c for c in columns
                                                 if c not in ("algorithm", "domain", "problem")]
    rows = sorted(({c: run.get(c) for c in head} for run in props.values()),
                  key=lambda r: (str(r["algorithm"]), str(r["domain"]), str(r["problem"])))
    out = Path(eval_dir)
    with open(out / "runs.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=head)
        w.writeheader()
        w.writerows(rows)
    (out / "runs.json").write_text(json.dumps(rows, indent=1) + "\n")
    with open(out / "coverage.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["domain", "algorithm", "runs", "solved"])
        w.writerows(coverage_rows(props))
    print(f"wrote {out / 'runs.csv'}, {out / 'runs.json'}, {out / 'coverage.csv'}")


def cached_revisions(revisions, cache):
    """NAME -> the htngtp binary of each git revision, built once into the cache."""
    from lab.cached_revision import CachedRevision

    target = Path(cache) / "cargo-target"
    build = ["sh", "-c", f"cargo build --release -p htngtp --target-dir '{target}' && "
             f"cp '{target}/release/htngtp' htngtp"]
    out = {}
    for name, rev in revisions.items():
        known = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--verify", "--quiet",
                                f"{rev}^{{commit}}"], capture_output=True)
        if known.returncode != 0:
            fail(f"--revision {name}={rev}: not a commit of {ROOT}")
        cr = CachedRevision(str(cache), str(ROOT), rev, build)
        cr.cache()
        binary = cr.path / "htngtp"
        if not binary.is_file():
            fail(f"--revision {name}={rev}: the build left no binary at {binary}")
        out[name] = binary
    return out


def help_formatter():
    return argparse.RawDescriptionHelpFormatter
