#!/usr/bin/env python3
"""The withheld cases of the gap diagnosis over several seeds: how often each case passes.

One seed's table (diagnose_gap --cases, docs/gap/cases.md) is one draw of every case's noise and
placement: a case near a criterion's edge passes at one seed and fails at the next. This reads
the cases.md of several runs (diagnose_gap --cases --seed S --out DIR/seed-S) and prints, per
case, the seeds it passes at and what was selected at each, as a Markdown table; then how
often the 95 % interval of a selected effect that was injected (one parameter, in every cell)
holds the injected size, read from each case's gap.json (DIR/seed-S/cases/): the interval
gap.json gives, and the fit's own (`over_folds.ci95_fit`, where the refits widened it); an
effect fitted per scenario counts once per scenario; and how often the interval of a selected,
injected effect's discrete width (width_px: the profile over the widths) holds the injected
width. Last, for each case of one effect of one
parameter injected in every cell, its size against the detection limit on that side that each
seed's table gives (gap.json `detection_limits`: the higher of the fit's own test, 80 % power,
and the share of the gap the keep rule asks, read in the whole gap or in the metrics the effect
moves; the test's alone in its own column), and at how many seeds the effect was found (selected, or named as one of a confounded set).
The limit of reference is the median over the tables without effect of the same runs (where
the case has their number of observations): the campaign's, not swollen by the effect itself.

Usage: gap_cases_seeds.py DIR/seed-1/cases.md DIR/seed-2/cases.md ...
  The seed of each file is read from its folder's name (seed-S), else its position (1, 2, ...).
"""
import json
import os
import re
import sys


def read_table(path):
    """{case: (selected, pass)} in the table's order."""
    rows = {}
    with open(path, encoding="utf-8") as f:
        lines = f.read().splitlines()
    header = None
    for line in lines:
        if not line.startswith("| "):
            if header is not None and rows:
                break
            continue
        cols = [c.strip() for c in line.strip().strip("|").split("|")]
        if header is None:
            header = cols
            continue
        if set(cols[0]) <= set("-"):
            continue
        rec = dict(zip(header, cols))
        if "case" not in rec or "pass" not in rec:
            raise ValueError("%s: not a cases table (no case or pass column)" % path)
        rows[rec["case"]] = (rec.get("selected", ""), rec["pass"].strip("*") == "yes",
                             rec.get("injected", ""))
    if not rows:
        raise ValueError("%s: no cases table" % path)
    return rows


def json_name(case):
    """The file diagnose_gap --cases writes a case's gap.json to: every other byte of its name
    than a letter or a digit becomes _."""
    return "".join(chr(b) if chr(b).isascii() and chr(b).isalnum() else "_"
                   for b in case.encode("utf-8")) + ".json"


def injected_sizes(text):
    """{effect: (param, value)} of the one-parameter effects injected in every cell."""
    out = {}
    for name, params in re.findall(r"(\w+) \(([^)]*)\)", text):
        parts = [p.strip() for p in params.split(",")]
        if len(parts) != 1:
            continue  # two parameters, or a light only
        kv = parts[0].split()
        if len(kv) == 2:
            try:
                out[name] = (kv[0], float(kv[1]))
            except ValueError:
                pass
    return out


def coverage(path, case, injected):
    """[(holds, fit_holds)] for the case's selected effects that were injected."""
    json_path = os.path.join(os.path.dirname(path), "cases", json_name(case))
    if not os.path.exists(json_path):
        return []
    with open(json_path, encoding="utf-8") as f:
        gap = json.load(f)
    out = []
    for sel in gap.get("selected") or []:
        if sel.get("name") not in injected:
            continue
        param, truth = injected[sel["name"]]
        folds = sel.get("over_folds") or {}
        if sel.get("scope") == "shared":
            groups = [((sel.get("ci95") or {}).get(param), folds)]
        else:  # per light or per scenario: each group's interval
            groups = [(((sel.get("ci95") or {}).get(s) or {}).get(param), folds.get(s) or {})
                      for s in (sel.get("ci95") or {})]
        for ci, spread in groups:
            if not ci or None in ci:
                continue
            fit = spread.get("ci95_fit") or ci
            out.append((ci[0] <= truth <= ci[1], fit[0] <= truth <= fit[1]))
    return out


def injected_widths(text):
    """{effect: width} of the effects injected in every cell with a discrete width (width_px)."""
    out = {}
    for name, params in re.findall(r"(\w+) \(([^)]*)\)", text):
        values = {}
        for part in params.split(","):
            kv = part.split()
            try:
                values[kv[0]] = float(kv[1]) if len(kv) == 2 else None
            except (ValueError, IndexError):
                values[part] = None  # "sunset only": not in every cell
        if None not in values.values() and "width_px" in values:
            out[name] = values["width_px"]
    return out


def width_coverage(path, case, injected):
    """[holds] for the widths of the case's selected effects that were injected: each group's
    interval (gap.json ci95, the profile over the widths) against the injected width."""
    gap = load_gap(path, case)
    out = []
    for sel in (gap or {}).get("selected") or []:
        if sel.get("name") not in injected:
            continue
        ci = sel.get("ci95") or {}
        groups = [ci] if sel.get("scope") == "shared" else [g or {} for g in ci.values()]
        for group in groups:
            lo_hi = group.get("width_px")
            if lo_hi and None not in lo_hi:
                out.append(lo_hi[0] <= injected[sel["name"]] <= lo_hi[1])
    return out


def load_gap(path, case):
    json_path = os.path.join(os.path.dirname(path), "cases", json_name(case))
    if not os.path.exists(json_path):
        return None
    with open(json_path, encoding="utf-8") as f:
        return json.load(f)


def limit_row(gap, effect, truth):
    """(limit, the test's limit, found) on the injected side from one seed's gap.json; a limit
    beyond the grid is infinite, None where the table gives none."""
    found = any(s.get("name") == effect for s in gap.get("selected") or [])
    found = found or any(effect in (a.get("one_of") or []) for a in gap.get("ambiguous") or [])
    for e in (gap.get("detection_limits") or {}).get("effects") or []:
        if e.get("effect") != effect or e.get("neutral") is None:
            continue
        side = e.get("above" if truth > e["neutral"] else "below")
        if side is None:
            return None, None, found
        inf = float("inf") if truth > e["neutral"] else float("-inf")
        size = side.get("size")
        test = side.get("by_test")
        return (inf if size is None else size), (inf if test is None else test), found
    return None, None, found


def null_limits(paths):
    """{(effect, side): [size, ...]} over the tables without effect (cases/null_*.json) of every
    run, and their number of observations; a size beyond the grid is infinite."""
    out, observations = {}, None
    for path in paths:
        folder = os.path.join(os.path.dirname(path), "cases")
        for name in sorted(os.listdir(folder)) if os.path.isdir(folder) else []:
            if not re.match(r"null_\d+\.json$", name):
                continue
            with open(os.path.join(folder, name), encoding="utf-8") as f:
                limits = json.load(f).get("detection_limits") or {}
            observations = limits.get("observations", observations)
            for e in limits.get("effects") or []:
                for side in ("below", "above"):
                    if e.get(side) is not None:
                        size = e[side].get("size")
                        inf = float("inf") if side == "above" else float("-inf")
                        out.setdefault((e["effect"], side), []).append(
                            inf if size is None else size)
    return out, observations


def median(values):
    values = sorted(values, key=abs)
    return values[len(values) // 2]


def limits_table(runs, paths):
    """Each one-effect case's size against the detection limits: on the tables without effect
    (the campaign's, where the case has their number of observations) and on the case's own
    tables (which hold the effect, so their gap is larger)."""
    nulls, null_obs = null_limits(paths)
    rows = []
    for case in list(runs[0][1]):
        if is_real(case):  # a real table's own limits size them (gap.json)
            continue
        injected_text = runs[0][1][case][2]
        sizes = injected_sizes(injected_text)
        if len(sizes) != 1 or len(re.findall(r"\w+ \(", injected_text)) != 1:
            continue
        effect, (param, truth) = next(iter(sizes.items()))
        limits, tests, found, neutral, observations = [], [], 0, 0.0, None
        for (seed, table), path in zip(runs, paths):
            gap = load_gap(path, case) if case in table else None
            if gap is None:
                continue
            lim, test, hit = limit_row(gap, effect, truth)
            found += hit
            observations = (gap.get("detection_limits") or {}).get("observations")
            for e in (gap.get("detection_limits") or {}).get("effects") or []:
                if e.get("effect") == effect and e.get("neutral") is not None:
                    neutral = e["neutral"]
            if lim is not None:
                limits.append(lim)
                tests.append(test)
        if not limits:
            continue
        side = "above" if truth > neutral else "below"
        reference = nulls.get((effect, side)) if observations == null_obs else None
        ref = median(reference) if reference else median(limits)
        rows.append((case, "%s %s" % (param, fmt(truth)),
                     "%s (%s to %s)" % (fmt(ref), fmt(min(reference, key=abs)),
                                        fmt(max(reference, key=abs))) if reference else "-",
                     fmt(median(limits)), fmt(median(tests)),
                     abs(truth - neutral) / max(abs(ref - neutral), 1e-12), found))
    if not rows:
        return
    print()
    print("| case | injected | limit without effect: median (range) | limit on its own tables | "
          "the test's alone | injected / limit | found |")
    print("|---|---|---|---|---|---|---|")
    for case, inj, ref, own, test, ratio, found in rows:
        print("| %s | %s | %s | %s | %s | %.2f | %d of %d |" % (case, inj, ref, own, test, ratio,
                                                               found, len(runs)))


# The cases injected into real tables (lib/gap/cases_real.cpp), counted apart.
REAL_CASE = re.compile(r" \+ .* \((0\.5|1\.5) × its limit\)$")


def is_real(case):
    return bool(REAL_CASE.search(case))


def is_real_outside(case):
    """An effect outside the registry injected into a real table (counted apart)."""
    return is_real(case) and ", outside (" in case


def fmt(v):
    return "%.3g" % v if v not in (float("inf"), float("-inf")) else "beyond the grid"


def main(argv):
    if len(argv) < 2 or argv[1] in ("-h", "--help"):
        print(__doc__.strip())
        return 0 if len(argv) >= 2 else 2
    runs = []
    for i, path in enumerate(argv[1:], 1):
        m = re.search(r"seed-(\d+)", path)
        try:
            runs.append((int(m.group(1)) if m else i, read_table(path)))
        except (OSError, ValueError) as e:
            print("gap_cases_seeds: %s" % e, file=sys.stderr)
            return 2
    cases = list(runs[0][1])
    for _, table in runs[1:]:
        cases += [c for c in table if c not in cases]
    n = len(runs)
    print("| case | passes | seeds passing | selected, seed by seed |")
    print("|---|---|---|---|")
    total = real_total = outside_total = 0
    for case in cases:
        passing = [str(s) for s, t in runs if case in t and t[case][1]]
        if is_real_outside(case):
            outside_total += len(passing)
        elif is_real(case):
            real_total += len(passing)
        elif not case.startswith("no effect"):
            total += len(passing)
        selected = "; ".join("%d: %s" % (s, t[case][0]) if case in t else "%d: -" % s
                             for s, t in runs)
        print("| %s | %d of %d | %s | %s |" % (case, len(passing), n, ", ".join(passing) or "-",
                                             selected))
    with_effect = [c for c in cases if not c.startswith("no effect") and not is_real(c)]
    real = [c for c in cases if is_real(c) and not is_real_outside(c)]
    outside = [c for c in cases if is_real_outside(c)]
    print()
    print("Cases with an effect or outside it: %d passes of %d (%d cases x %d seeds)."
          % (total, len(with_effect) * n, len(with_effect), n))
    if real:
        print("Effects injected into real tables: %d passes of %d (%d cases x %d seeds)."
              % (real_total, len(real) * n, len(real), n))
    if outside:
        print("Effects outside the registry injected into real tables: %d passes of %d "
              "(%d cases x %d seeds)." % (outside_total, len(outside) * n, len(outside), n))
    held = []
    for (seed, table), path in zip(runs, argv[1:]):
        for case, (_, _, injected) in table.items():
            if is_real(case):  # a real table's interval holds its own size too
                continue
            held += coverage(path, case, injected_sizes(injected))
    if held:
        print("95 %% intervals of selected, injected effects that hold the injected size "
              "(simulated cases): "
              "%d of %d (the fit's own: %d of %d)."
              % (sum(h for h, _ in held), len(held), sum(f for _, f in held), len(held)))
    widths = []
    for (seed, table), path in zip(runs, argv[1:]):
        for case, (_, _, injected) in table.items():
            if not is_real(case):
                widths += width_coverage(path, case, injected_widths(injected))
    if widths:
        print("Widths of selected, injected effects whose 95 %% interval (the profile over the "
              "widths) holds the injected width: %d of %d." % (sum(widths), len(widths)))
    limits_table(runs, argv[1:])
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
