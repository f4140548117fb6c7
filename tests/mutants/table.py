#!/usr/bin/env python3
"""The RESULTS.md table of a mutation run: per module, mutants, caught, missed, timeouts,
unviable and the score (caught + timeouts that hang, over the viable mutants).

Usage: tests/mutants/table.py [RESULTS_DIR...]   (default: every out/mutants/runs/*)
       tests/mutants/table.py --before [RESULTS_DIR...]
                             (each mutant's first outcome instead: the score before the
                             tests written for survivors)
       tests/mutants/table.py --names caught|tested [RESULTS_DIR...]
                             (the mutants an earlier run caught, or tested at all, one
                             name a line: what tests/mutants/run --again/--untested skip)

Reads each RESULTS_DIR/mutants.out/outcomes.json (cargo-mutants' record); with several
(shards, or a later run of the mutants still missed), a mutant's last outcome counts, the
runs taken in the order they started. A timeout counts as
caught only when it is listed in tests/mutants/hangs.txt (checked by hand to hang, not to
be merely slow); the others count as missed.
"""
import glob
import json
import os
import sys
from collections import defaultdict

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")


def outcomes(dirs, first=False):
    last = {}
    paths = [os.path.join(d, "mutants.out", "outcomes.json") for d in dirs]
    records = []
    for path in paths:
        if os.path.exists(path):
            with open(path) as f:
                records.append(json.load(f))
    # A run started later tests a later tree (newer tests): its outcome counts.
    for record in sorted(records, key=lambda r: r["start_time"]):
        for o in record["outcomes"]:
            s = o["scenario"]
            if not isinstance(s, dict) or "Mutant" not in s:
                continue  # the baseline
            name = s["Mutant"]["name"]
            if not (first and name in last):
                last[name] = (s["Mutant"]["file"], o["summary"])
    return last


def hangs():
    path = os.path.join(ROOT, "tests", "mutants", "hangs.txt")
    if not os.path.exists(path):
        return set()
    with open(path) as f:
        return {l.strip() for l in f if l.strip() and not l.startswith("#")}


def reasons():
    """Survivor name -> why it is left, from tests/mutants/survivors.md."""
    path = os.path.join(ROOT, "tests", "mutants", "survivors.md")
    out = {}
    if os.path.exists(path):
        with open(path) as f:
            for line in f:
                if line.startswith("- src/") and " — " in line:
                    name, why = line[2:].rstrip("\n").split(" — ", 1)
                    out[name] = why
    return out


def main():
    args = sys.argv[1:]
    names = None
    first = args[:1] == ["--before"]
    if first:
        args = args[1:]
    if args[:1] == ["--names"]:
        if len(args) < 2 or args[1] not in ("caught", "tested"):
            sys.exit("table.py: --names takes caught or tested")
        names, args = args[1], args[2:]
    dirs = args or glob.glob(os.path.join(ROOT, "out", "mutants", "runs", "*"))
    hung = hangs()
    if names:
        done = {"CaughtMutant", "Unviable"}
        for name, (_, summary) in sorted(outcomes(dirs).items()):
            caught = summary in done or (summary == "Timeout" and name in hung)
            if names == "tested" or caught:
                print(name)
        return
    rows = defaultdict(lambda: defaultdict(int))
    missed = []
    for name, (file, summary) in sorted(outcomes(dirs, first).items()):
        r = rows[file]
        r["mutants"] += 1
        if summary == "CaughtMutant":
            r["caught"] += 1
        elif summary == "MissedMutant":
            r["missed"] += 1
            missed.append(name)
        elif summary == "Timeout":
            r["timeouts"] += 1
            if name in hung:
                r["hung"] += 1
            else:
                missed.append(name + "  (timeout, not known to hang)")
        elif summary == "Unviable":
            r["unviable"] += 1
        else:
            r["other"] += 1
            missed.append(f"{name}  ({summary})")
    print("| module | mutants | caught | missed | timeouts (hang) | unviable | score |")
    print("|---|---:|---:|---:|---:|---:|---:|")
    total = defaultdict(int)
    for file in sorted(rows):
        r = rows[file]
        for k, v in r.items():
            total[k] += v
        print(row(file.removeprefix("src/"), r))
    print(row("**all**", total))
    if missed:
        why = reasons()
        unexplained = [m for m in missed if m.split("  (")[0] not in why]
        print(f"\nNot caught ({len(missed)}; {len(unexplained)} without a reason in survivors.md):")
        for m in missed:
            print("-", m, "—", why.get(m.split("  (")[0], "NO REASON GIVEN"))


def row(name, r):
    viable = r["mutants"] - r["unviable"]
    caught = r["caught"] + r["hung"]
    score = f"{100.0 * caught / viable:.1f} %" if viable else "-"
    return (
        f"| {name} | {r['mutants']} | {r['caught']} | {r['missed']} | "
        f"{r['timeouts']} ({r['hung']}) | {r['unviable']} | {score} |"
    )


if __name__ == "__main__":
    main()
