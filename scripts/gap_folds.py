#!/usr/bin/env python3
"""What each outer fold of a gap diagnosis fitted, and where its selection earns or loses.

diagnose_gap's nested cross-validation (lib/gap/README.md) holds one distance out at a time,
fits the calibration and a selection on the other cells, then simulates the held-out cells with
the fold's calibrated base and with its selection. gap.json keeps, per fold
(how_far.nested.folds[]), the selection's values (`params`), each scenario's σ_d and hole
probability in the calibrated base and beside the selection (`calibration`), and each metric's
Σz² on the held-out cells as simulated with either (`simulated_sq_per_metric`). This prints them
fold by fold: the selection and its values, the scenarios whose σ_d or hole probability the
selection moved by more than --moved (a share, default 0.01), and each metric's simulated Σz²
with the calibrated base and with the selection, largest loss first. A metric that loses where
the selection was meant to act elsewhere is where the fold's fit traded one metric for another.

Every figure is checked against the fold's totals (the metrics' Σz² add up to
simulated_calibrated_sq and simulated_sq, within gap.json's 6 significant digits; one params
entry per selected effect; one calibration entry per scenario): a gap.json that does not hold together stops with a one-line error (exit 2).

Usage: scripts/gap_folds.py GAP_JSON [--moved 0.01]
"""

import argparse
import json
import math
import sys


def fail(msg):
    print(f"gap_folds: {msg}", file=sys.stderr)
    sys.exit(2)


def number(v):
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("gap_json")
    ap.add_argument("--moved", type=float, default=0.01,
                    help="relative change of σ_d or hole probability worth listing (0.01)")
    a = ap.parse_args()
    if not (a.moved >= 0):
        fail(f"--moved {a.moved}: must be >= 0")
    try:
        with open(a.gap_json, encoding="utf-8") as f:
            gap = json.load(f)
    except OSError as e:
        fail(f"{a.gap_json}: cannot read: {e.strerror}")
    except (json.JSONDecodeError, UnicodeDecodeError) as e:
        fail(f"{a.gap_json}: not JSON: {e}")
    nested = (gap.get("how_far") or {}).get("nested") if isinstance(gap, dict) else None
    if not isinstance(nested, dict) or not isinstance(nested.get("folds"), list):
        fail(f"{a.gap_json}: no how_far.nested.folds (a diagnosis run with --no-nested?)")
    scenarios = [s.get("scenario") for s in gap.get("calibration", {}).get("scenarios", [])]
    for i, fold in enumerate(nested["folds"]):
        where = f"{a.gap_json}: fold {i + 1} ({fold.get('held', '?')})"
        for key in ("selected", "params", "calibration", "simulated_sq_per_metric"):
            if key not in fold:
                fail(f"{where}: no '{key}' (a gap.json from before the folds' fits were written)")
        selected = fold["selected"]
        for key in ("params", "calibration", "simulated_sq_per_metric"):
            if not isinstance(fold[key], dict):
                fail(f"{where}: '{key}' is not an object")
        if not isinstance(selected, list) or sorted(fold["params"]) != sorted(selected):
            fail(f"{where}: params name {sorted(fold['params'])}, the selection {selected}")
        fitted = fold["calibration"].get("scenarios", [])
        if [s.get("scenario") for s in fitted] != scenarios:
            fail(f"{where}: calibration scenarios differ from the table's {scenarios}")
        per = fold["simulated_sq_per_metric"]
        print(f"{fold['held']} ({fold['cells']} cells held out): "
              f"{', '.join(selected) if selected else 'nothing selected'}")
        for e in selected:
            print(f"  {e}: {json.dumps(fold['params'][e])}")
        for s in fitted:
            for key in ("sigma_d_px", "invalid_prob"):
                c, v = (s.get(key) or {}).get("calibrated"), (s.get(key) or {}).get("selected")
                if not (number(c) and number(v)):
                    fail(f"{where}: {s['scenario']} {key} is not a number")
                if c > 0 and abs(v / c - 1) > a.moved:
                    print(f"  {s['scenario']}: {key} {c:.4g} -> {v:.4g} "
                          f"({100 * (v / c - 1):+.1f} % beside the selection)")
        if not fold.get("simulated"):
            print("  not simulated on its held-out cells")
            continue
        cal, sel = per.get("calibrated"), per.get("selected")
        if not isinstance(cal, dict) or not isinstance(sel, dict) or sorted(cal) != sorted(sel) \
                or not cal:
            fail(f"{where}: simulated_sq_per_metric lists different metrics")
        for name, total in (("calibrated", cal), ("selected", sel)):
            key = "simulated_calibrated_sq" if name == "calibrated" else "simulated_sq"
            whole = fold.get(key)
            if not all(number(x) for x in total.values()) or not number(whole):
                fail(f"{where}: {key} or its metrics are not numbers")
            # gap.json writes 6 significant digits: each figure within 5e-6 of its value.
            rounding = 5e-6 * (sum(abs(x) for x in total.values()) + abs(whole)) + 1e-9
            if abs(sum(total.values()) - whole) > rounding:
                fail(f"{where}: the metrics' Σz² add up to {sum(total.values()):.6g}, "
                     f"{key} is {whole:.6g}")
        print(f"  simulated Σz², calibrated -> selection: "
              f"{fold['simulated_calibrated_sq']:.1f} -> {fold['simulated_sq']:.1f}")
        for m in sorted(cal, key=lambda m: cal[m] - sel[m]):
            print(f"    {m}: {cal[m]:.1f} -> {sel[m]:.1f} ({sel[m] - cal[m]:+.1f})")


if __name__ == "__main__":
    main()
