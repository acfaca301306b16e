#!/usr/bin/env python3
"""Pictures of the sim-to-real gap: where it lies (real - sim heat maps by distance x angle,
per scenario and metric), which effect explains it (the ranking with its held-out shrink), and
how far it shrinks (before / after).

Two inputs:
  --gap DIR/gap.json   the gap report of diagnose_gap (DESIGN.md, "Gap report"): all three
                       figures;
  --real R.csv --sim S.csv
                       without a report: real - sim straight from two metrics CSVs (e.g. the
                       article's table and `simulate --protocol config/protocol_paper.yaml
                       --metrics-only`), in the metrics' own units: the heat maps only.

Figures written into --out-dir: gap_heatmaps.png (1500 x 1300 px), and from a report also
gap_effects.png (1300 x 700 px) and gap_before_after.png (1400 x 650 px).

What is read from gap.json (unknown keys are ignored; a missing part leaves its figure with a
note, not an error):
  effects[]        name, params {p: value}, ci95 {p: [lo, hi]} (or one [lo, hi] for a single
                   parameter), delta_bic, shrink_in_sample_pct, shrink_heldout_pct; best first.
  selected         a name, a list of names, or of objects with "name".
  confounded       a list of groups: [a, b], {"effects": [a, b], ...}, {"a": .., "b": ..}, or
                   "a~b" / "a,b" strings.
  baseline_gap, remaining_gap
                   a number, or {label: number}, or {label: {"rms_scaled" | "rms" | "value" |
                   "gap" | "in_sample" | "heldout": number}}: drawn as bars before / after.
  per-cell rows    a list under "cells", "per_cell", "cell_rows", "per_cell_rows" or "rows".
                   A row names its cell with light, preset, [emitter], distance_m (or
                   distance), angle_deg (or angle); [heldout | held_out | withheld]: true for
                   cells kept out of the fit. Its values come either
                   - one metric per row ("long"): "metric" and the gap in the first of
                     gap_scaled, scaled_gap, z, gap, real_minus_sim, delta (or real - sim),
                     the gap after the selected effects in the first of gap_after_scaled,
                     remaining_scaled, gap_after, remaining_gap, remaining, after;
                   - all metrics in one row ("wide"): nested {"gap": {metric: v}, "gap_after"
                     (or "remaining"): {metric: v}} (or "real"/"sim" objects), or flat keys
                     <metric>_gap / gap_<metric> and <metric>_gap_after / <metric>_remaining.
                   Rows of one cell with several emitter settings are averaged (the heat map
                   has one value per light x preset x distance x angle).

Usage: plot_gap.py --gap gap.json --out-dir DIR
       plot_gap.py --real real.csv --sim sim.csv --out-dir DIR
"""
import argparse
import json
import math
import os
import sys

import plot_common as pc

HEAT_FIGSIZE = (15, 13)
EFFECTS_FIGSIZE = (13, 7)
BEFORE_AFTER_FIGSIZE = (14, 6.5)
CELL_LIST_KEYS = ("cells", "per_cell", "cell_rows", "per_cell_rows", "rows")
BEFORE_KEYS = ("gap_scaled", "scaled_gap", "z", "gap", "real_minus_sim", "delta")
AFTER_KEYS = ("gap_after_scaled", "remaining_scaled", "gap_after", "remaining_gap", "remaining",
              "after")
HELDOUT_KEYS = ("heldout", "held_out", "withheld")
SCALAR_KEYS = ("rms_scaled", "rms", "value", "gap", "in_sample", "heldout", "mean_abs")
# Metrics of the CSV fallback: label, unit, real - sim of one matched pair of rows.
CSV_METRICS = [
    ("median bias", "m", lambda r, s: r["median_m"] - s["median_m"]),
    ("mean - median", "m", lambda r, s: (r["mean_m"] - r["median_m"]) -
     (s["mean_m"] - s["median_m"])),
    ("plane_std", "m", lambda r, s: r["plane_std_m"] - s["plane_std_m"]),
    ("valid_pct", "points", lambda r, s: r["valid_pct"] - s["valid_pct"]),
]


def first_number(obj, keys):
    for k in keys:
        v = obj.get(k)
        if isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v):
            return float(v)
    return None


def get_any(obj, keys, default=None):
    for k in keys:
        if k in obj:
            return obj[k]
    return default


# --- reading a report ---------------------------------------------------------------------------

def cell_of(row, path):
    light = row.get("light")
    preset = row.get("preset")
    dist = get_any(row, ("distance_m", "distance"))
    ang = get_any(row, ("angle_deg", "angle"))
    if light is None or preset is None or dist is None or ang is None:
        raise pc.InputError(f"{path}: a per-cell row lacks light, preset, distance_m or "
                            f"angle_deg: {json.dumps(row)[:120]}")
    try:
        return (str(light), str(preset), float(dist), float(ang))
    except (TypeError, ValueError):
        raise pc.InputError(f"{path}: a per-cell row has a non-numeric distance or angle")


def per_cell_values(doc, path):
    """[(cell, metric, before, after or None, heldout bool)] from the report's per-cell rows."""
    rows = None
    for key in CELL_LIST_KEYS:
        if isinstance(doc.get(key), list):
            rows = doc[key]
            break
    if rows is None:
        return [], False
    out = []
    scaled = False
    for row in rows:
        if not isinstance(row, dict):
            raise pc.InputError(f"{path}: per-cell rows must be objects")
        cell = cell_of(row, path)
        held = bool(get_any(row, HELDOUT_KEYS, False))
        if "metric" in row:  # long: one metric per row
            before = first_number(row, BEFORE_KEYS)
            if before is None and isinstance(row.get("real"), (int, float)) and \
                    isinstance(row.get("sim"), (int, float)):
                before = float(row["real"]) - float(row["sim"])
            if before is None:
                continue
            scaled = scaled or any(k in row for k in ("gap_scaled", "scaled_gap", "z"))
            out.append((cell, str(row["metric"]), before, first_number(row, AFTER_KEYS), held))
            continue
        # wide: nested objects of metrics, or flat <metric>_gap keys
        nested_before = get_any(row, ("gap_scaled", "gap", "real_minus_sim"))
        nested_after = get_any(row, ("gap_after_scaled", "gap_after", "remaining", "after"))
        if isinstance(nested_before, dict):
            scaled = scaled or isinstance(row.get("gap_scaled"), dict)
            for metric, v in nested_before.items():
                if isinstance(v, (int, float)):
                    after = nested_after.get(metric) if isinstance(nested_after, dict) else None
                    out.append((cell, metric, float(v),
                                float(after) if isinstance(after, (int, float)) else None, held))
        elif isinstance(row.get("real"), dict) and isinstance(row.get("sim"), dict):
            for metric, v in row["real"].items():
                s = row["sim"].get(metric)
                if isinstance(v, (int, float)) and isinstance(s, (int, float)):
                    out.append((cell, metric, float(v) - float(s), None, held))
        else:
            for key, v in row.items():
                metric = None
                if key.endswith("_gap") and not key.startswith("gap_"):
                    metric = key[:-4]
                elif key.startswith("gap_") and key[4:] not in ("after", "scaled"):
                    metric = key[4:]
                if metric is None or not isinstance(v, (int, float)):
                    continue
                after = first_number(row, (f"{metric}_gap_after", f"{metric}_remaining",
                                           f"gap_after_{metric}"))
                out.append((cell, metric, float(v), after, held))
    return out, scaled


def scalars(value, prefix=""):
    """{label: number} from a number, {label: number} or {label: {key: number}}."""
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return {prefix or "all": float(value)}
    out = {}
    if isinstance(value, dict):
        direct = first_number(value, SCALAR_KEYS)
        if direct is not None and prefix:
            return {prefix: direct}
        for k, v in value.items():
            label = f"{prefix} {k}".strip()
            if isinstance(v, (int, float)) and not isinstance(v, bool):
                out[label] = float(v)
            elif isinstance(v, dict):
                n = first_number(v, SCALAR_KEYS)
                if n is not None:
                    out[label] = n
    return out


def names_of(value):
    if value is None:
        return []
    if isinstance(value, str):
        return [value]
    if isinstance(value, dict):
        return [value["name"]] if "name" in value else []
    if isinstance(value, list):
        out = []
        for v in value:
            out += names_of(v)
        return out
    return []


def confounded_groups(value):
    groups = []
    for g in value or []:
        if isinstance(g, list):
            groups.append([str(x) for x in g if isinstance(x, str)])
        elif isinstance(g, dict):
            if isinstance(g.get("effects"), list):
                groups.append([str(x) for x in g["effects"]])
            else:
                groups.append([str(v) for k, v in g.items() if k in ("a", "b", "c")])
        elif isinstance(g, str):
            groups.append([x.strip() for x in g.replace("~", ",").split(",") if x.strip()])
    return [g for g in groups if len(g) >= 2]


def read_report(path):
    if not os.path.isfile(path):
        raise pc.InputError(f"{path}: no such file")
    with open(path) as f:
        try:
            doc = json.load(f)
        except json.JSONDecodeError as e:
            raise pc.InputError(f"{path}: not JSON ({e.msg}, line {e.lineno})")
    if not isinstance(doc, dict):
        raise pc.InputError(f"{path}: not a gap report (a JSON object expected)")
    if not any(k in doc for k in ("effects", "baseline_gap") + CELL_LIST_KEYS):
        raise pc.InputError(f"{path}: not a gap report (none of effects, baseline_gap, "
                            "per-cell rows)")
    return doc


# --- the CSV fallback ---------------------------------------------------------------------------

def csv_values(real_path, sim_path):
    need = ["light", "emitter", "preset", "distance_m", "angle_deg", "mean_m", "median_m",
            "plane_std_m", "valid_pct"]

    def table(path):
        out = {}
        for r in pc.ok_rows(pc.read_csv(path, need)):
            key = (r["light"], r["preset"], r["emitter"], pc.number(r, "distance_m", path),
                   pc.number(r, "angle_deg", path))
            out[key] = {c: pc.number(r, c, path) for c in need[5:]}
        return out

    real, sim = table(real_path), table(sim_path)
    common = [k for k in real if k in sim]
    if not common:
        raise pc.InputError(f"{sim_path}: no row matches a row of {real_path} (light, preset, "
                            "emitter, distance, angle)")
    values = []
    for k in common:
        for label, unit, fn in CSV_METRICS:
            values.append(((k[0], k[1], k[3], k[4]), f"{label} [{unit}]", fn(real[k], sim[k]),
                           None, False))
    return values, len(common), len(real), len(sim)


# --- figures ------------------------------------------------------------------------------------

def mean_by_cell(values):
    """{metric: {cell: (mean before, mean after or None, any held out)}} over emitter rows."""
    acc = {}
    for cell, metric, before, after, held in values:
        d = acc.setdefault(metric, {}).setdefault(cell, [[], [], False])
        d[0].append(before)
        if after is not None:
            d[1].append(after)
        d[2] = d[2] or held
    return {m: {c: (sum(v[0]) / len(v[0]), sum(v[1]) / len(v[1]) if v[1] else None, v[2])
                for c, v in cells.items()} for m, cells in acc.items()}


def heatmaps(values, out, title, unit_note):
    by_metric = mean_by_cell(values)
    metrics = list(by_metric)[:6]
    scen = sorted({(c[0], c[1]) for m in metrics for c in by_metric[m]},
                  key=lambda s: pc.scenario_key(*s))[:4]
    fig, axes = pc.plt.subplots(len(metrics), len(scen), figsize=HEAT_FIGSIZE, squeeze=False,
                                layout="constrained")
    cmap = pc.plt.get_cmap("RdBu_r")
    for i, metric in enumerate(metrics):
        cells = by_metric[metric]
        vmax = max(abs(v[0]) for v in cells.values()) or 1.0
        image = None
        for j, (light, preset) in enumerate(scen):
            ax = axes[i][j]
            mine = {(c[2], c[3]): v for c, v in cells.items() if (c[0], c[1]) == (light, preset)}
            dists = sorted({k[0] for k in mine})
            angs = sorted({k[1] for k in mine})
            grid = [[mine[(d, a)][0] if (d, a) in mine else float("nan") for d in dists]
                    for a in angs]
            image = ax.imshow(grid, cmap=cmap, vmin=-vmax, vmax=vmax, origin="lower",
                              aspect="auto")
            for ai, a in enumerate(angs):
                for di, d in enumerate(dists):
                    if (d, a) not in mine:
                        continue
                    v, _, held = mine[(d, a)]
                    digits = 0 if vmax >= 10 else 1 if vmax >= 2 else 2
                    text = f"{v:+.{digits}f}"
                    if float(text) == 0:
                        text = f"{0:.{digits}f}"  # no "-0.0"
                    ax.text(di, ai, text + ("*" if held else ""), ha="center",
                            va="center", fontsize=9,
                            color="white" if abs(v) > 0.6 * vmax else "black")
            ax.set_xticks(range(len(dists)), [f"{d:g}" for d in dists])
            ax.set_yticks(range(len(angs)), [f"{a:g}°" for a in angs])
            if i == 0:
                ax.set_title(pc.scenario_title(light, preset), fontsize=11)
            if i == len(metrics) - 1:
                ax.set_xlabel("distance [m]")
            if j == 0:
                ax.set_ylabel(f"{metric}\nangle")
        fig.colorbar(image, ax=axes[i, :], shrink=0.9, label=metric)
    fig.suptitle(title + "\n" + unit_note, fontsize=13)
    pc.save(fig, out)


def note_figure(size, text, out):
    fig = pc.plt.figure(figsize=size)
    fig.text(0.5, 0.5, text, ha="center", va="center", fontsize=14, wrap=True)
    pc.save(fig, out)


def effects_figure(doc, out):
    effects = [e for e in doc.get("effects") or [] if isinstance(e, dict) and "name" in e]
    if not effects:
        note_figure(EFFECTS_FIGSIZE, "gap.json lists no effects", out)
        return
    selected = set(names_of(doc.get("selected")))
    groups = confounded_groups(doc.get("confounded"))
    partners = {}
    for g in groups:
        for n in g:
            partners.setdefault(n, set()).update(x for x in g if x != n)
    fig, (ax, axb) = pc.plt.subplots(1, 2, figsize=EFFECTS_FIGSIZE, sharey=True,
                                     width_ratios=[3, 1], layout="constrained")
    ys = list(range(len(effects)))[::-1]  # best first, at the top
    held = [first_number(e, ("shrink_heldout_pct",)) for e in effects]
    ins = [first_number(e, ("shrink_in_sample_pct",)) for e in effects]
    h = 0.38
    ax.barh([y + h / 2 for y in ys], [v or 0 for v in ins], height=h, color="0.75",
            label="in-sample shrink")
    ax.barh([y - h / 2 for y in ys], [v or 0 for v in held], height=h, color="tab:blue",
            label="held-out shrink")
    labels = []
    for e in effects:
        params = e.get("params") or {}
        ci = e.get("ci95")
        parts = []
        if isinstance(params, dict):
            for p, v in params.items():
                text = f"{p} = {v:.3g}" if isinstance(v, (int, float)) else f"{p} = {v}"
                band = ci.get(p) if isinstance(ci, dict) else (ci if len(params) == 1 else None)
                if isinstance(band, list) and len(band) == 2 and \
                        all(isinstance(b, (int, float)) for b in band):
                    text += f" [{band[0]:.3g}, {band[1]:.3g}]"
                parts.append(text)
        name = e["name"] + ("  ★ selected" if e["name"] in selected else "")
        if e["name"] in partners:
            name += "\n(confounded with " + ", ".join(sorted(partners[e["name"]])) + ")"
        labels.append(name + ("\n" + "; ".join(parts) if parts else ""))
    ax.set_yticks(ys, labels, fontsize=9)
    for y, v in zip(ys, held):
        if v is not None:
            ax.text(max(v, 0) + 1, y - h / 2, f"{v:.0f}%", va="center", fontsize=9)
    ax.axvline(0, color="k", lw=0.8)
    ax.set_xlabel("gap shrink [%] (held out: cells that took no part in the fit)")
    ax.legend(loc="lower right")
    ax.grid(axis="x", alpha=0.3)
    bic = [first_number(e, ("delta_bic",)) for e in effects]
    axb.barh(ys, [b or 0 for b in bic], color=["tab:green" if (b or 0) < 0 else "tab:red"
                                               for b in bic])
    span = max([abs(b) for b in bic if b is not None] or [1.0])
    for y, b in zip(ys, bic):
        if b is None:
            axb.text(0, y, " no ΔBIC", va="center", fontsize=9)
        elif abs(b) > 0.35 * span:  # inside the bar
            axb.text(b / 2, y, f"{b:.1f}", va="center", ha="center", fontsize=9, color="white")
        else:
            axb.text(b, y, f" {b:.1f} " if b >= 0 else f"{b:.1f} ", va="center",
                     ha="left" if b >= 0 else "right", fontsize=9)
    axb.axvline(0, color="k", lw=0.8)
    axb.set_xlabel("ΔBIC (negative: better than none)")
    axb.grid(axis="x", alpha=0.3)
    fig.suptitle("Candidate effects, each fitted alone, best first: how much of the gap each "
                 "explains\n(parameter = value [95% interval])", fontsize=13)
    pc.save(fig, out)


def before_after_figure(doc, values, out, path):
    before = scalars(doc.get("baseline_gap"))
    after = scalars(doc.get("remaining_gap"))
    fig, (ax, axs) = pc.plt.subplots(1, 2, figsize=BEFORE_AFTER_FIGSIZE, layout="constrained")
    labels = [k for k in before if k in after] or list(before)
    if labels:
        xs = range(len(labels))
        w = 0.38
        ax.bar([x - w / 2 for x in xs], [before[k] for k in labels], width=w, color="0.6",
               label="baseline gap")
        ax.bar([x + w / 2 for x in xs], [after.get(k, float("nan")) for k in labels], width=w,
               color="tab:blue", label="remaining gap (selected effects added)")
        for x, k in zip(xs, labels):
            if k in after and before[k]:
                ax.text(x + w / 2, after[k], f"{100 * (after[k] / before[k] - 1):+.0f}%",
                        ha="center", va="bottom", fontsize=9)
        ax.set_xticks(list(xs), labels, rotation=20, ha="right")
        ax.legend()
        ax.set_ylabel("gap (as in gap.json)")
        ax.grid(axis="y", alpha=0.3)
    else:
        ax.text(0.5, 0.5, "no baseline_gap / remaining_gap numbers", ha="center",
                transform=ax.transAxes)
    ax.set_title("Whole gap before and after")
    pairs = [(m, b, a, h) for _, m, b, a, h in values if a is not None]
    if pairs:
        metrics = list(dict.fromkeys(p[0] for p in pairs))
        colors = pc.plt.get_cmap("tab10")
        lim = max(max(abs(p[1]), abs(p[2])) for p in pairs) * 1.05
        for i, m in enumerate(metrics):
            for held, style in ((False, dict(color=colors(i))),
                                (True, dict(facecolors="none", edgecolors=colors(i)))):
                pts = [p for p in pairs if p[0] == m and p[3] == held]
                if pts:
                    axs.scatter([abs(p[1]) for p in pts], [abs(p[2]) for p in pts], s=28,
                                label=f"{m}" + (" (held out)" if held else ""), **style)
        axs.plot([0, lim], [0, lim], "k", lw=0.8, label="no change")
        axs.set_xlim(0, lim)
        axs.set_ylim(0, lim)
        axs.set_xlabel("|gap| before, per cell")
        axs.set_ylabel("|gap| after, per cell")
        axs.legend(fontsize=8, loc="upper left")
        axs.grid(alpha=0.3)
    else:
        axs.text(0.5, 0.5, f"{os.path.basename(path)} has no per-cell after values",
                 ha="center", transform=axs.transAxes)
    axs.set_title("Per cell: below the diagonal, the gap shrank")
    fig.suptitle("The gap before and after the selected effects "
                 f"({', '.join(names_of(doc.get('selected'))) or 'none selected'})")
    pc.save(fig, out)


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--gap", help="gap.json of diagnose_gap")
    ap.add_argument("--real", help="real metrics CSV (without --gap)")
    ap.add_argument("--sim", help="simulated metrics CSV (without --gap)")
    ap.add_argument("--out-dir", required=True)
    args = ap.parse_args()
    heat = os.path.join(args.out_dir, "gap_heatmaps.png")
    if args.gap:
        if args.real or args.sim:
            raise pc.InputError("--gap and --real/--sim: give one or the other")
        doc = read_report(args.gap)
        values, scaled = per_cell_values(doc, args.gap)
        if values:
            note = ("real - sim scaled by each metric's noise" if scaled else
                    "real - sim as in gap.json") + "; mean over emitter rows; * held-out cell"
            heatmaps(values, heat, "Where the simulator departs from reality: real - sim per "
                     "cell", note)
        else:
            note_figure(HEAT_FIGSIZE, f"{args.gap} has no per-cell rows", heat)
        effects_figure(doc, os.path.join(args.out_dir, "gap_effects.png"))
        before_after_figure(doc, values, os.path.join(args.out_dir, "gap_before_after.png"),
                            args.gap)
        return
    if not (args.real and args.sim):
        raise pc.InputError("give --gap gap.json, or both --real and --sim")
    values, n, nr, ns = csv_values(args.real, args.sim)
    heatmaps(values, heat, "Where the simulator departs from reality: real - sim per cell "
             f"({os.path.basename(args.real)} - {os.path.basename(args.sim)})",
             f"metrics' own units; mean over emitter rows; {n} matched rows of {nr} real, "
             f"{ns} simulated")


if __name__ == "__main__":
    pc.run_main(sys.argv[0], main)
