#!/usr/bin/env python3
"""How often the gap diagnosis sees an effect injected into a real table at multiples of the
limit that table's own report publishes ("could go unseen up to ...").

Reads the runs of scripts/gap_limit_power.sh (diagnose_gap --cases --inject-into TABLE
--inject-times LIST, one folder a seed: DIR/seed-S/cases.md and DIR/seed-S/cases/*.json) and
prints, per table, effect and multiple, as a Markdown table:
- passes: the withheld suite's criteria (selected set equal to the injected one beside the
  table's own selection, size within 20 %, 70 % of the injected part's gap removed);
- selected as itself: the injected effect among those kept;
- found: selected, or named "one of" a set holding it (gap.json `ambiguous`).
  Both count an effect the table keeps or names without the injection too (the field unit's own
  offset): only "passes" reads the injection against the table as it is;
then the injected size at each multiple, seed by seed (the limit moves with the seed's
simulations).

Usage: gap_limit_power.py DIR/seed-1 DIR/seed-2 ...
"""
import json
import os
import re
import sys

CASE = re.compile(r"^(.+) \+ (\S+) \(([0-9.]+) × its limit\)$")


def file_name(case):
    """The case's gap.json name as diagnose_gap writes it: each byte not a letter or digit is _."""
    return re.sub(rb"[^A-Za-z0-9]", b"_", case.encode()).decode() + ".json"


def read_runs(folders):
    rows = {}  # (table, effect, multiple) -> [(seed, passed, selected, found, size)]
    for i, folder in enumerate(folders):
        m = re.search(r"seed-(\d+)/?$", folder)
        seed = int(m.group(1)) if m else i + 1
        path = os.path.join(folder, "cases.md")
        if not os.path.isfile(path):
            sys.exit(f"gap_limit_power: {path}: no such file (a run of diagnose_gap --cases --out)")
        with open(path, encoding="utf-8") as f:
            lines = [l for l in f.read().splitlines() if l.startswith("| ")]
        if not lines or not lines[0].startswith("| case |"):
            sys.exit(f"gap_limit_power: {path}: no table of cases")
        for line in lines[1:]:
            cells = [c.strip() for c in line.strip().strip("|").split("|")]
            if len(cells) < 8:
                sys.exit(f"gap_limit_power: {path}: a row with {len(cells)} columns")
            c = CASE.match(cells[0])
            if not c:
                continue
            table, effect, multiple = c.group(1), c.group(2), float(c.group(3))
            selected = [] if cells[2] == "none" else [s.strip() for s in cells[2].split(",")]
            size = re.search(r"\(\w+ ([-0-9.e]+)", cells[1])
            case_json = os.path.join(folder, "cases", file_name(cells[0]))
            try:
                with open(case_json, encoding="utf-8") as f:
                    ambiguous = json.load(f).get("ambiguous", [])
            except (OSError, ValueError) as e:
                sys.exit(f"gap_limit_power: {case_json}: {e}")
            named = any(effect in a.get("one_of", []) for a in ambiguous)
            rows.setdefault((table, effect, multiple), []).append(
                (seed, cells[7] == "yes", effect in selected, effect in selected or named,
                 size.group(1) if size else "?"))
    return rows


def main(argv):
    if len(argv) < 2:
        sys.exit(__doc__.split("Usage: ")[1].strip())
    rows = read_runs(argv[1:])
    if not rows:
        sys.exit("gap_limit_power: no case injected at a multiple of a limit in these runs")
    print("| table | effect | × limit | passes | selected as itself | found | injected, seed by seed |")
    print("|---|---|---|---|---|---|---|")
    for (table, effect, multiple), runs in sorted(rows.items()):
        runs.sort()
        n = len(runs)
        count = lambda k: sum(1 for r in runs if r[k])
        sizes = "; ".join(f"{r[0]}: {r[4]}" for r in runs)
        print(f"| {table} | {effect} | {multiple:g} | {count(1)} of {n} | {count(2)} of {n} | "
              f"{count(3)} of {n} | {sizes} |")


if __name__ == "__main__":
    main(sys.argv)
