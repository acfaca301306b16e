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
mean. The case must inject one registered effect in every cell, named by the case's first word
("disparity_offset small", "depth_scale large", "disparity_offset at the noise floor"), whose
parameters are continuous (not edge_mixing or region_spill, whose width is a whole pixel).

Usage: scripts/gap_size_spread.py --case "disparity_offset small" --seeds 6-25
           [--build BUILD_DIR] [--out DIR]
BUILD_DIR (default: build, from the project's root) holds apps/diagnose_gap. Each seed's outputs
go to DIR/seed-S, a folder that must not exist yet (a temporary folder, removed, without --out).
"""

import argparse
import glob
import json
import math
import os
import re
import shutil
import statistics
import subprocess
import sys
import tempfile


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
    """(effect, {param: value}) from the case's row of cases.md: 'effect (p v, q w)'."""
    with open(cases_md, encoding="utf-8") as f:
        for line in f:
            cols = [c.strip() for c in line.strip().strip("|").split("|")]
            if len(cols) > 2 and cols[0] == case:
                m = re.fullmatch(r"([a-z_]+) \(([^(),;]* [^(),;]*(?:, [^(),;]* [^(),;]*)*)\)",
                                 cols[1])
                if not m or " only" in cols[1]:
                    fail(f"case '{case}' injects '{cols[1]}': one registered effect in every "
                         "cell is needed")
                params = {}
                for item in m.group(2).split(","):
                    name, _, value = item.strip().partition(" ")
                    try:
                        params[name] = float(value)
                    except ValueError:
                        fail(f"{cases_md}: '{item}' is not 'param value'")
                return m.group(1), params
    fail(f"{cases_md}: no row for case '{case}'")


def run_seed(app, case, effect, seed, out):
    if os.path.exists(out):
        fail(f"{out} exists: give --out a folder without seed-S folders in it")
    cmd = [app, "--cases", "--seed", str(seed), "--case", case, "--out", out]
    cmd += ["--candidates", effect]
    r = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    if r.returncode != 0:
        last = (r.stderr.strip().splitlines() or ["(no message)"])[-1]
        fail(f"seed {seed}: diagnose_gap exited {r.returncode}: {last}")
    files = glob.glob(os.path.join(out, "cases", "*.json"))
    if len(files) != 1:
        fail(f"seed {seed}: expected one gap.json in {out}/cases, found {len(files)}")
    with open(files[0], encoding="utf-8") as f:
        return json.load(f)


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
        # gap.json, each parameter's neutral value (a case is read only when every parameter
        # has one and none is a discrete width, which the judge reads exactly).
        effect, params, neutral = args.case.split()[0], None, {}
        rows = []
        for seed in seeds:
            out = os.path.join(root, f"seed-{seed}")
            gap = run_seed(app, args.case, effect, seed, out)
            if params is None:
                injected, params = injected_of(os.path.join(out, "cases.md"), args.case)
                if injected != effect:
                    fail(f"case '{args.case}' injects {injected}, not {effect}")
                for e in gap.get("detection_limits", {}).get("effects", []):
                    if e.get("effect") == effect and not e.get("discrete", False):
                        neutral[e["param"]] = e["neutral"]
                missing = sorted(set(params) - set(neutral))
                if missing:
                    fail(f"{effect}: no continuous parameter's neutral value published for "
                         + ", ".join(missing)
                         + ": a case of one effect whose parameters are continuous is needed")
                if any(params[k] == neutral[k] for k in params):
                    fail(f"case '{args.case}' injects a neutral value")
            rows.append((seed, gap))
        print(f"case: {args.case}; injected: {effect} "
              + ", ".join(f"{k} {v:g}" for k, v in params.items())
              + f"; fitted alone; seeds {seeds[0]}-{seeds[-1]}")
        shared = {k: [] for k in params}
        within = 0
        for seed, gap in rows:
            fit = next((e for e in gap["effects"] if e["name"] == effect), None)
            if fit is None:
                print(f"  seed {seed}: not fitted")
                continue
            groups = ([fit["params"]] if fit["scope"] == "shared"
                      else list(fit["params"].values()))
            worst = 0.0
            for g in groups:
                for k, truth in params.items():
                    dep = truth - neutral[k]
                    err = abs(g[k] - truth) / abs(dep) if dep else math.inf
                    worst = max(worst, err)
            within += worst <= 0.2
            if fit["scope"] == "shared":
                for k in params:
                    shared[k].append(fit["params"][k])
                shown = ", ".join(f"{k} {fit['params'][k]:.4g}" for k in params)
            else:
                shown = "; ".join(f"{g}: " + ", ".join(f"{k} {v[k]:.4g}" for k in params)
                                  for g, v in fit["params"].items())
            print(f"  seed {seed}: {fit['scope']}: {shown}  (off by {100 * worst:.0f} %)")
        for k, v in shared.items():
            if len(v) < 2:
                print(f"{k}: fewer than two shared fits")
                continue
            mean, sd = statistics.mean(v), statistics.stdev(v)
            se = sd / math.sqrt(len(v))
            off = (f"{(mean - params[k]) / se:+.1f} standard errors of the mean" if se > 0
                   else "every fit equal")
            dep = params[k] - neutral[k]
            print(f"{k}: {len(v)} shared fits, mean {mean:.4g} (injected {params[k]:g}; "
                  f"mean − injected: {off}), "
                  f"one seed's spread {sd:.3g} = {100 * sd / abs(dep):.0f} % of the departure "
                  f"(20 % allowed)")
        print(f"within 20 %: {within} of {len(rows)} seeds")
    finally:
        if not args.out:
            shutil.rmtree(root, ignore_errors=True)


if __name__ == "__main__":
    main()
