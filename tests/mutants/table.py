#!/usr/bin/env python3
"""The RESULTS.md mutation table, rebuilt from the committed per-mutant outcomes.

Usage: tests/mutants/table.py             the table from tests/mutants/outcomes.tsv: per
                                          module, mutants, caught, missed, timeouts, unviable
                                          and the score (caught + timeouts that hang, over
                                          the viable mutants), the commits the outcomes were
                                          tested at, and every survivor with its class and
                                          reason from survivors.md. Exits 1 when a survivor
                                          has no reason, or a reason no class, or a reason
                                          in survivors.md names no survivor (its mutant now
                                          caught, or no longer generated: a stale reason).
       tests/mutants/table.py --record [RESULTS_DIR...]
                                          merge runs' outcomes (default: every
                                          out/mutants/runs/*, in the order they started, a
                                          mutant's last outcome counting) into outcomes.tsv,
                                          each with the commit its run tested (RESULTS_DIR/
                                          commit, which tests/mutants/run writes); then the
                                          table.
       tests/mutants/table.py --runs [RESULTS_DIR...]
                                          the table of runs not yet recorded (out/), without
                                          touching outcomes.tsv.
       tests/mutants/table.py --names caught|tested [RESULTS_DIR...]
                                          the mutants caught, or tested at all, by the
                                          committed outcomes and the runs, one name a line
                                          (what tests/mutants/run --again and --untested
                                          skip).

A timeout counts as caught only when it is listed in tests/mutants/hangs.txt (checked by
hand to hang, not merely slow); the others count as missed.

A survivor's reason in survivors.md starts with its class:
  equivalent          no input tells the mutant from the code (argued in the reason);
  host-only           an input can, but only in host time or host work: never a pixel, a
                      count or a cycle;
  tolerance-accepted  it changes reported counts within a stated tolerance, whose source the
                      reason names.
"""
import glob
import json
import os
import sys
from collections import defaultdict

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
HERE = os.path.join(ROOT, "tests", "mutants")
OUTCOMES = os.path.join(HERE, "outcomes.tsv")
CLASSES = ("equivalent", "host-only", "tolerance-accepted")
HEADER = (
    "# Per-mutant outcomes of tests/mutants/run, one a line: file, mutant name (as\n"
    "# cargo-mutants prints it), outcome (CaughtMutant, MissedMutant, Timeout, Unviable)\n"
    "# and the commit its run tested. Written by tests/mutants/table.py --record;\n"
    "# tests/mutants/table.py rebuilds RESULTS.md's table from it.\n"
)


def run_outcomes(dirs):
    """name -> (file, summary, commit) from runs' outcomes.json, later runs winning."""
    records = []
    for d in dirs:
        path = os.path.join(d, "mutants.out", "outcomes.json")
        if not os.path.exists(path):
            continue
        with open(path) as f:
            record = json.load(f)
        commit_path = os.path.join(d, "commit")
        commit = "unknown"
        if os.path.exists(commit_path):
            with open(commit_path) as f:
                commit = f.read().strip() or "unknown"
        records.append((record, commit))
    last = {}
    # A run started later tests a later tree (newer tests): its outcome counts.
    for record, commit in sorted(records, key=lambda r: r[0]["start_time"]):
        for o in record["outcomes"]:
            s = o["scenario"]
            if not isinstance(s, dict) or "Mutant" not in s:
                continue  # the baseline
            last[s["Mutant"]["name"]] = (s["Mutant"]["file"], o["summary"], commit)
    return last


def committed():
    """name -> (file, summary, commit) from outcomes.tsv (empty when it is absent)."""
    out = {}
    if not os.path.exists(OUTCOMES):
        return out
    with open(OUTCOMES) as f:
        for n, line in enumerate(f, 1):
            if line.startswith("#") or not line.strip():
                continue
            parts = line.rstrip("\n").split("\t")
            if len(parts) != 4:
                sys.exit(f"{OUTCOMES}:{n}: expected 4 tab-separated fields, found {len(parts)}")
            file, name, summary, commit = parts
            out[name] = (file, summary, commit)
    return out


def record(dirs):
    """Merges the runs' outcomes into outcomes.tsv; returns the merged outcomes."""
    merged = committed()
    new = run_outcomes(dirs)
    if not new:
        sys.exit("table.py --record: no outcomes.json under " + ", ".join(dirs or ["out/mutants/runs"]))
    merged.update(new)
    with open(OUTCOMES, "w") as f:
        f.write(HEADER)
        for name, (file, summary, commit) in sorted(merged.items(), key=lambda kv: (kv[1][0], kv[0])):
            f.write(f"{file}\t{name}\t{summary}\t{commit}\n")
    print(f"recorded {len(new)} outcomes into {os.path.relpath(OUTCOMES)} ({len(merged)} in all)\n")
    return merged


def hangs():
    path = os.path.join(HERE, "hangs.txt")
    if not os.path.exists(path):
        return set()
    with open(path) as f:
        return {l.strip() for l in f if l.strip() and not l.startswith("#")}


def reasons():
    """Survivor name -> why it is left, from tests/mutants/survivors.md."""
    path = os.path.join(HERE, "survivors.md")
    out = {}
    if os.path.exists(path):
        with open(path) as f:
            for line in f:
                if line.startswith("- src/") and " — " in line:
                    name, why = line[2:].rstrip("\n").split(" — ", 1)
                    out[name] = why
    return out


def class_of(why):
    """The class a reason starts with ("equivalent: ..."), or None."""
    head = why.split(":", 1)[0].split(" (", 1)[0].strip()
    return head if head in CLASSES else None


def table(outcomes, whole=True):
    """Prints the table and the survivors; returns how many survivors lack a true reason,
    plus, when `outcomes` is the whole set (not `--runs`), how many reasons are stale."""
    hung = hangs()
    rows = defaultdict(lambda: defaultdict(int))
    missed = []
    for name, (file, summary, _) in sorted(outcomes.items()):
        r = rows[file]
        r["mutants"] += 1
        if summary == "CaughtMutant":
            r["caught"] += 1
        elif summary == "MissedMutant":
            r["missed"] += 1
            missed.append((name, ""))
        elif summary == "Timeout":
            r["timeouts"] += 1
            if name in hung:
                r["hung"] += 1
            else:
                missed.append((name, "timeout, not known to hang"))
        elif summary == "Unviable":
            r["unviable"] += 1
        else:
            r["other"] += 1
            missed.append((name, summary))
    commits = sorted({c for (_, _, c) in outcomes.values()})
    print("Tested at " + ", ".join(commits) + ".\n")
    print("| module | mutants | caught | missed | timeouts (hang) | unviable | score |")
    print("|---|---:|---:|---:|---:|---:|---:|")
    total = defaultdict(int)
    for file in sorted(rows):
        r = rows[file]
        for k, v in r.items():
            total[k] += v
        print(row(file.removeprefix("src/"), r))
    print(row("**all**", total))
    why = reasons()
    by_class = defaultdict(int)
    wrong = 0
    lines = []
    for name, note in missed:
        reason = why.get(name)
        cls = class_of(reason) if reason else None
        if cls is None:
            wrong += 1
            shown = reason or "NO REASON GIVEN"
            lines.append(f"- {name}{'  (' + note + ')' if note else ''} — NO CLASS: {shown}")
        else:
            by_class[cls] += 1
            lines.append(f"- {name}{'  (' + note + ')' if note else ''} — {reason}")
    if missed:
        counts = ", ".join(f"{by_class[c]} {c}" for c in CLASSES)
        print(f"\nNot caught ({len(missed)}: {counts}; {wrong} without a classed reason in survivors.md):")
        print("\n".join(lines))
    if whole:
        survivors = {name for name, _ in missed}
        stale = sorted(name for name in why if name not in survivors)
        if stale:
            print(f"\nStale reasons in survivors.md ({len(stale)}: the mutant is caught or gone):")
            print("\n".join(f"- {name}" for name in stale))
        wrong += len(stale)
    return wrong


def row(name, r):
    viable = r["mutants"] - r["unviable"]
    caught = r["caught"] + r["hung"]
    score = f"{100.0 * caught / viable:.1f} %" if viable else "-"
    return (
        f"| {name} | {r['mutants']} | {r['caught']} | {r['missed']} | "
        f"{r['timeouts']} ({r['hung']}) | {r['unviable']} | {score} |"
    )


def main():
    args = sys.argv[1:]
    runs_default = lambda rest: rest or glob.glob(os.path.join(ROOT, "out", "mutants", "runs", "*"))
    if args[:1] == ["--names"]:
        if len(args) < 2 or args[1] not in ("caught", "tested"):
            sys.exit("table.py: --names takes caught or tested")
        which, dirs = args[1], runs_default(args[2:])
        hung = hangs()
        done = {"CaughtMutant", "Unviable"}
        # The committed outcomes, then the runs not yet recorded (out/, which a fresh
        # checkout lacks), a run's outcome counting over the committed one as --record does.
        outcomes = committed()
        outcomes.update(run_outcomes(dirs))
        for name, (_, summary, _) in sorted(outcomes.items()):
            caught = summary in done or (summary == "Timeout" and name in hung)
            if which == "tested" or caught:
                print(name)
        return 0
    if args[:1] == ["--record"]:
        outcomes = record(runs_default(args[1:]))
    elif args[:1] == ["--runs"]:
        return 1 if table(run_outcomes(runs_default(args[1:])), whole=False) else 0
    elif args:
        sys.exit(__doc__)
    else:
        outcomes = committed()
        if not outcomes:
            sys.exit(f"table.py: no committed outcomes in {os.path.relpath(OUTCOMES)}: run tests/mutants/run, then table.py --record")
    return 1 if table(outcomes) else 0


if __name__ == "__main__":
    sys.exit(main())
