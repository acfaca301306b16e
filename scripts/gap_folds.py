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

Everything is checked before anything is printed: one params entry per selected effect, one
calibration entry per scenario of the table, the metrics' Σz² adding up to the fold's
simulated_calibrated_sq and simulated_sq, and each metric's Σz² with the selection equal to the
sum over the fold's held-out cells of their own z (cells[].nested.z_simulated), all within
gap.json's 6 significant digits. A gap.json that does not hold together stops with one line
naming the file and what is wrong (exit 2).

Usage: scripts/gap_folds.py GAP_JSON [--moved 0.01]
"""

import argparse
import json
import math
import re
import sys


class Bad(Exception):
    pass


def fail(msg):
    print(f"gap_folds: {msg}", file=sys.stderr)
    sys.exit(2)


def number(v):
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def obj(v, what):
    if not isinstance(v, dict):
        raise Bad(f"{what} is not an object")
    return v


def arr(v, what):
    if not isinstance(v, list):
        raise Bad(f"{what} is not a list")
    return v


def num(v, what):
    if not number(v):
        raise Bad(f"{what} is not a number")
    return v


def within(a, b, rel):
    """a and b agree to the rounding of figures written with 6 significant digits."""
    return abs(a - b) <= rel * (abs(a) + abs(b)) + 1e-9


def held_cells_sq(cells, held, metrics):
    """Σ z_simulated² per metric over the cells the fold held out; None if `held` names no
    distance."""
    m = re.fullmatch(r"distance ([0-9.]+) m", held)
    if not m:
        return None
    distance = float(m.group(1))
    sums = {k: 0.0 for k in metrics}
    for i, c in enumerate(cells):
        c = obj(c, f"cells[{i}]")
        if num(c.get("distance_m"), f"cells[{i}].distance_m") != distance:
            continue
        z = obj(obj(c.get("nested"), f"cells[{i}].nested").get("z_simulated"),
                f"cells[{i}].nested.z_simulated")
        for k in metrics:
            v = z.get(k)
            if v is not None:
                sums[k] += num(v, f"cells[{i}].nested.z_simulated.{k}") ** 2
    return sums


def read_folds(gap, moved):
    """The report's lines, fold by fold; raises Bad on the first inconsistency."""
    gap = obj(gap, "the file")
    nested = obj(obj(gap.get("how_far"), "how_far").get("nested"),
                 "how_far.nested (a diagnosis run without the outer hold-out?)")
    folds = arr(nested.get("folds"), "how_far.nested.folds")
    if not folds:
        raise Bad("how_far.nested.folds is empty")
    scenarios = [obj(s, "calibration.scenarios[]").get("scenario") for s in
                 arr(obj(gap.get("calibration"), "calibration").get("scenarios"),
                     "calibration.scenarios")]
    cells = arr(gap.get("cells"), "cells")
    lines = []
    for i, fold in enumerate(folds):
        fold = obj(fold, f"fold {i + 1}")
        held = fold.get("held")
        if not isinstance(held, str):
            raise Bad(f"fold {i + 1}: no 'held'")
        where = f"fold {i + 1} ({held})"
        for key in ("params", "calibration", "simulated_sq_per_metric"):
            if key not in fold:
                raise Bad(f"{where}: no '{key}' (a gap.json from before the folds' fits were "
                          "written)")
        selected = arr(fold.get("selected"), f"{where}: selected")
        if not all(isinstance(e, str) for e in selected):
            raise Bad(f"{where}: selected holds a name that is not a string")
        params = obj(fold["params"], f"{where}: params")
        if sorted(params) != sorted(selected):
            raise Bad(f"{where}: params name {sorted(params)}, the selection {selected}")
        fitted = arr(obj(fold["calibration"], f"{where}: calibration").get("scenarios"),
                     f"{where}: calibration.scenarios")
        if [obj(s, f"{where}: calibration.scenarios[]").get("scenario")
                for s in fitted] != scenarios:
            raise Bad(f"{where}: calibration scenarios differ from the table's {scenarios}")
        simulated = fold.get("simulated")
        if not isinstance(simulated, bool):
            raise Bad(f"{where}: simulated is not true or false")
        cells_held = fold.get("cells")
        lines.append(f"{held} ({cells_held} cells held out): "
                     f"{', '.join(selected) if selected else 'nothing selected'}")
        for e in selected:
            lines.append(f"  {e}: {json.dumps(params[e])}")
        for s in fitted:
            for key in ("sigma_d_px", "invalid_prob"):
                pair = obj(s.get(key), f"{where}: {s['scenario']} {key}")
                c = num(pair.get("calibrated"), f"{where}: {s['scenario']} {key}.calibrated")
                v = num(pair.get("selected"), f"{where}: {s['scenario']} {key}.selected")
                if c > 0 and abs(v / c - 1) > moved:
                    lines.append(f"  {s['scenario']}: {key} {c:.4g} -> {v:.4g} "
                                 f"({100 * (v / c - 1):+.1f} % beside the selection)")
        if not simulated:
            lines.append("  not simulated on its held-out cells")
            continue
        per = obj(fold["simulated_sq_per_metric"], f"{where}: simulated_sq_per_metric")
        cal = obj(per.get("calibrated"), f"{where}: simulated_sq_per_metric.calibrated")
        sel = obj(per.get("selected"), f"{where}: simulated_sq_per_metric.selected")
        if sorted(cal) != sorted(sel) or not cal:
            raise Bad(f"{where}: simulated_sq_per_metric lists different metrics")
        for name, total, key in (("calibrated", cal, "simulated_calibrated_sq"),
                                 ("selected", sel, "simulated_sq")):
            whole = num(fold.get(key), f"{where}: {key}")
            values = [num(x, f"{where}: simulated_sq_per_metric.{name}") for x in
                      total.values()]
            # Each figure within 5e-6 of its value (%.6g).
            if abs(sum(values) - whole) > 5e-6 * (sum(map(abs, values)) + abs(whole)) + 1e-9:
                raise Bad(f"{where}: the metrics' Σz² add up to {sum(values):.6g}, {key} is "
                          f"{whole:.6g}")
        own = held_cells_sq(cells, held, sel)
        if own is not None:
            for k, v in sel.items():
                if not within(v, own[k], 2e-5):  # z² of a 6-digit z: within 1e-5 of its value
                    raise Bad(f"{where}: {k}'s Σz² with the selection is {v:.6g}, its held-out "
                              f"cells' own z give {own[k]:.6g}")
        lines.append(f"  simulated Σz², calibrated -> selection: "
                     f"{fold['simulated_calibrated_sq']:.1f} -> {fold['simulated_sq']:.1f}")
        for m in sorted(cal, key=lambda m: cal[m] - sel[m]):
            lines.append(f"    {m}: {cal[m]:.1f} -> {sel[m]:.1f} ({sel[m] - cal[m]:+.1f})")
    return lines


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
    try:
        lines = read_folds(gap, a.moved)
    except Bad as e:
        fail(f"{a.gap_json}: {e}")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
