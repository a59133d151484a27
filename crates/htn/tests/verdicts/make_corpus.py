#!/usr/bin/env python3
"""Builds the verdict corpus: htngtp's plans for shared benchmark problems and broken variants of
them, each checked by the official verifier (pandaPIparser --verify), whose verdict is stored in
verdicts.tsv. See README.md.

usage: make_corpus.py VERIFIER LIST
LIST: lines `PLAN DOMAIN PROBLEM` (absolute paths; PLAN an htngtp plan in the competition format).
"""
import os, re, subprocess, sys

HERE = os.path.dirname(os.path.abspath(__file__))
SHARED = "/work/shared/"
ANSI = re.compile(r"\x1b\[[0-9;]*m")


def verify(verifier, dom, prob, text):
    path = "/tmp/corpus-candidate.plan"
    with open(path, "w") as f:
        f.write(text)
    r = subprocess.run([verifier, "--verify", dom, prob, path], capture_output=True, text=True, timeout=120)
    out = ANSI.sub("", r.stdout)
    failed = [l.split(":")[0].strip() for l in out.splitlines() if l.endswith(": false") and "result" not in l]
    ok = r.returncode == 0 and "Plan verification result: true" in out
    return ok, (failed[0] if failed else ("" if ok else "parse or other failure"))


def lines(text):
    body = [l for l in text.splitlines() if l.strip() and l.strip() not in ("==>", "<==")]
    root = next(i for i, l in enumerate(body) if l.startswith("root"))
    return body[:root], body[root], body[root + 1:]


def join(actions, root, decs):
    return "==>\n" + "\n".join(actions + [root] + decs) + "\n<==\n"


def mutations(text):
    """(name, broken plan text) pairs; several candidates per kind, first that fits is kept."""
    acts, root, decs = lines(text)
    out = []
    low = join([l.lower() for l in acts], root, [d.lower() for d in decs])
    if low != join(acts, root, decs):
        out.append(("lowercase-names", [low]))
    cands = []
    for i, a in enumerate(acts):
        w = a.split()
        for j in range(1, len(w)):
            alt = w[j].swapcase()
            if alt != w[j]:
                v = w[:j] + [alt] + w[j + 1:]
                cands.append(join(acts[:i] + [" ".join(v)] + acts[i + 1:], root, decs))
                break
    out.append(("case-of-one-name", cands[:3]))
    cands = []
    for i, d in enumerate(decs):
        w = d.split()
        k = w.index("->") + 1
        alt = w[k].upper() if w[k] != w[k].upper() else w[k].lower()
        v = w[:k] + [alt] + w[k + 1:]
        cands.append(join(acts, root, decs[:i] + [" ".join(v)] + decs[i + 1:]))
    out.append(("case-of-method", cands[:2]))
    cands = []
    for i, a in enumerate(acts):
        w = a.split()
        if len(w) >= 4 and w[2] != w[3]:
            v = w[:2] + [w[3], w[2]] + w[4:]
            cands.append(join(acts[:i] + [" ".join(v)] + acts[i + 1:], root, decs))
    out.append(("swapped-arguments", cands[:3]))
    if decs:
        out.append(("missing-decomposition", [join(acts, root, decs[:-1])]))
    cands = []
    for i in range(len(acts) - 1):
        if acts[i].split()[1:] != acts[i + 1].split()[1:]:
            cands.append(join(acts[:i] + [acts[i + 1], acts[i]] + acts[i + 2:], root, decs))
    out.append(("wrong-order", cands[:3]))
    # Another object at the same position of the same action elsewhere in the plan.
    cands = []
    by_pos = {}
    for a in acts:
        w = a.split()
        for j in range(2, len(w)):
            by_pos.setdefault((w[1], j), set()).add(w[j])
    for i, a in enumerate(acts):
        w = a.split()
        for j in range(2, len(w)):
            for o in sorted(by_pos[(w[1], j)] - {w[j]}):
                v = w[:j] + [o] + w[j + 1:]
                cands.append(join(acts[:i] + [" ".join(v)] + acts[i + 1:], root, decs))
    out.append(("other-argument", cands[:12]))
    if acts:
        out.append(("dropped-action", [join(acts[:-1], root, decs)]))
        # The official verifier drops arguments beyond an action's parameters (a warning).
        out.append(("extra-argument", [join([acts[0] + " " + acts[-1].split()[-1]] + acts[1:], root, decs)]))
        w = acts[0].split()
        if len(w) > 2:
            w[2] = "undeclared-object"
            out.append(("undeclared-object", [join([" ".join(w)] + acts[1:], root, decs)]))
    ids = root.split()[1:]
    if len(ids) > 1:
        out.append(("root-reversed", [join(acts, "root " + " ".join(reversed(ids)), decs)]))
    out.append(("no-root-line", ["==>\n" + "\n".join(acts) + "\n<==\n"]))
    return out


def main():
    verifier, listing = sys.argv[1], sys.argv[2]
    rows = []
    for line in open(listing):
        parts = line.split()
        if len(parts) != 3:
            continue
        plan, dom, prob = parts
        base = os.path.basename(plan)[: -len(".plan")]
        text = open(plan).read()
        ok, why = verify(verifier, dom, prob, text)
        rows.append(emit(base, "as-planned", text, dom, prob, ok, why))
        seen_inexec = False
        for kind, cands in mutations(text):
            for c in cands:
                ok, why = verify(verifier, dom, prob, c)
                # For `other-argument`, prefer a plan whose methods instantiate but does not run.
                if kind == "other-argument" and why != "Plan is executable" and c is not cands[-1]:
                    continue
                rows.append(emit(base, kind, c, dom, prob, ok, why))
                break
    with open(os.path.join(HERE, "verdicts.tsv"), "w") as f:
        f.write("# plan\tdomain (relative to ../shared)\tproblem (relative to ../shared)\tofficial verdict\tfirst check the official verifier failed\n")
        for r in rows:
            f.write("\t".join(r) + "\n")


def emit(base, kind, text, dom, prob, ok, why):
    name = f"{base}--{kind}.plan"
    with open(os.path.join(HERE, "plans", name), "w") as f:
        f.write(text)
    rel = lambda p: os.path.relpath(os.path.normpath(p), SHARED)
    print(name, ok, why, flush=True)
    return [f"plans/{name}", rel(dom), rel(prob), "valid" if ok else "invalid", why or "-"]


if __name__ == "__main__":
    main()
