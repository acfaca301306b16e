#!/usr/bin/env python3
"""How precisely the gap diagnosis sizes one injected effect, over many draws of a withheld case.

The strict suite (scripts/gap_cases.sh) asks every injected size back within 20 % of its
departure from the neutral value, on five seeds. This runs one case of one registered effect
(docs/gap/cases.md) at each seed of a range, diagnosed with that effect as the only candidate
(`diagnose_gap --cases --case NAME --candidates EFFECT`), so that the figure is the fit's own
precision and not the selection's: every seed is a new draw of the table's placements and noise.
It prints each seed's fitted size and then, over the seeds fitted in one shared value, the mean,
its standard error, the spread of one seed and the share within 20 % (the judge's size
criterion, read on the fit whether or not the diagnosis selects it). A seed whose fit is per
light or per scenario is listed and counted in the share by its worst group, but left out of the
mean. The case must inject one registered effect of one parameter in every cell, named by the
case's first word ("disparity_offset small", "depth_scale large", "disparity_offset at the noise
floor"; not edge_mixing or region_spill, of two parameters). The case's row and gap.json are read
as scripts/gap_cases_seeds.py reads them.

Usage: scripts/gap_size_spread.py --case "disparity_offset small" --seeds 6-25
           [--build BUILD_DIR] [--out DIR]
BUILD_DIR (default: build, from the project's root) holds apps/diagnose_gap. Each seed's outputs
go to DIR/seed-S, a folder that must not exist yet (a temporary folder, removed, without --out).
"""

import argparse
import math
import os
import re
import shutil
import statistics
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from gap_cases_seeds import injected_sizes, load_gap, read_table  # noqa: E402


def fail(msg):
    print(f"gap_size_spread: {msg}", file=sys.stderr)
    sys.exit(2)


def parse_seeds(text):
    m = re.fullmatch(r"([1-9][0-9]*)(?:-([1-9][0-9]*))?", text)
    if not m:
        fail(f"--seeds: '{text}' is not S or A-B with positive integers")
    a = int(m.group(1))
    b = int(m.group(2) or a)
    if b < a:
        fail(f"--seeds: '{text}' ends before it starts")
    return list(range(a, b + 1))


def injected_of(cases_md, case):
    """(effect, param, value) of the case's one effect of one parameter, injected in every cell,
    from its row of cases.md."""
    try:
        row = read_table(cases_md).get(case)
    except ValueError as e:
        fail(str(e))
    if row is None:
        fail(f"{cases_md}: no row for case '{case}'")
    text = row[2]
    sizes = injected_sizes(text)
    if len(sizes) != 1 or len(re.findall(r"\w+ \(", text)) != 1:
        fail(f"case '{case}' injects '{text}': one registered effect of one parameter in every "
             "cell is needed")
    effect, (param, value) = next(iter(sizes.items()))
    return effect, param, value


def run_seed(app, case, effect, seed, out):
    if os.path.exists(out):
        fail(f"{out} exists: give --out a folder without seed-S folders in it")
    cmd = [app, "--cases", "--seed", str(seed), "--case", case, "--out", out]
    cmd += ["--candidates", effect]
    r = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    if r.returncode != 0:
        last = (r.stderr.strip().splitlines() or ["(no message)"])[-1]
        fail(f"seed {seed}: diagnose_gap exited {r.returncode}: {last}")
    gap = load_gap(os.path.join(out, "cases.md"), case)
    if gap is None:
        fail(f"seed {seed}: diagnose_gap wrote no gap.json for '{case}' in {out}/cases")
    return gap


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--case", required=True,
                    help="a case of one registered effect of continuous parameters")
    ap.add_argument("--seeds", required=True, help="S or A-B")
    ap.add_argument("--build", default=os.environ.get("BUILD_DIR") or os.path.join(
        os.path.dirname(os.path.abspath(__file__)), "..", "build"))
    ap.add_argument("--out", help="keep each seed's outputs in OUT/seed-S")
    args = ap.parse_args()
    seeds = parse_seeds(args.seeds)
    if args.case.startswith(("unit", "field")) or not re.fullmatch(r"[a-z_]+ .+", args.case):
        fail(f"case '{args.case}': the case's name must start with its effect (the unit and "
             "field cases are not read)")
    if "+" in args.case or " only" in args.case or "outside" in args.case or \
            args.case.startswith("no effect"):
        fail(f"case '{args.case}': a case of one registered effect in every cell is needed "
             "(\"EFFECT small\", \"EFFECT large\", \"disparity_offset at the noise floor\")")
    if args.out and os.path.exists(args.out) and (not os.path.isdir(args.out)
                                                  or os.listdir(args.out)):
        fail(f"--out {args.out}: not an empty folder")
    app = os.path.join(args.build, "apps", "diagnose_gap")
    if not os.access(app, os.X_OK):
        fail(f"{app} not built (run scripts/build.sh)")
    root = args.out or tempfile.mkdtemp(prefix="gap_size_spread.")
    try:
        # The case's first word names its effect; its row of cases.md, the injection; the first
        # gap.json, the parameter's neutral value.
        effect, param, truth, neutral = args.case.split()[0], None, None, None
        rows = []
        for seed in seeds:
            out = os.path.join(root, f"seed-{seed}")
            gap = run_seed(app, args.case, effect, seed, out)
            if param is None:
                injected, param, truth = injected_of(os.path.join(out, "cases.md"), args.case)
                if injected != effect:
                    fail(f"case '{args.case}' injects {injected}, not {effect}")
                neutral = next((e["neutral"] for e in gap.get("detection_limits", {})
                                .get("effects", []) if e.get("effect") == effect and
                                e.get("param") == param), None)
                if neutral is None:
                    fail(f"{effect}: no neutral value of {param} published")
                if truth == neutral:
                    fail(f"case '{args.case}' injects the neutral value")
            rows.append((seed, gap))
        departure = abs(truth - neutral)
        print(f"case: {args.case}; injected: {effect} {param} {truth:g}; fitted alone; "
              f"seeds {seeds[0]}-{seeds[-1]}")
        shared, within = [], 0
        for seed, gap in rows:
            fit = next((e for e in gap["effects"] if e["name"] == effect), None)
            if fit is None:
                print(f"  seed {seed}: not fitted")
                continue
            if fit["scope"] == "shared":
                groups = {"": fit["params"]}
                shared.append(fit["params"][param])
            else:
                groups = fit["params"]
            worst = max(abs(g[param] - truth) for g in groups.values()) / departure
            within += worst <= 0.2
            shown = "; ".join(f"{name + ': ' if name else ''}{param} {g[param]:.4g}"
                              for name, g in groups.items())
            print(f"  seed {seed}: {fit['scope']}: {shown}  (off by {100 * worst:.0f} %)")
        if len(shared) < 2:
            print(f"{param}: fewer than two shared fits")
        else:
            mean, sd = statistics.mean(shared), statistics.stdev(shared)
            se = sd / math.sqrt(len(shared))
            off = (f"{(mean - truth) / se:+.1f} standard errors of the mean" if se > 0
                   else "every fit equal")
            print(f"{param}: {len(shared)} shared fits, mean {mean:.4g} (injected {truth:g}; "
                  f"mean − injected: {off}), one seed's spread {sd:.3g} = "
                  f"{100 * sd / departure:.0f} % of the departure (20 % allowed)")
        print(f"within 20 %: {within} of {len(rows)} seeds")
    finally:
        if not args.out:
            shutil.rmtree(root, ignore_errors=True)


if __name__ == "__main__":
    main()
