#!/usr/bin/env python3
"""Pictures of the sim-to-real gap: where it lies (real - sim heat maps by distance x angle,
per scenario and metric), which effect explains it (the ranking with its held-out shrink), and
how far it shrinks (before / after).

Two inputs:
  --gap DIR/gap.json   the report of diagnose_gap (its schema: README, "gap.json"): all three
                       figures;
  --real R.csv --sim S.csv
                       without a report: real - sim straight from two metrics CSVs (e.g. the
                       article's table and `simulate --protocol config/protocol_paper.yaml
                       --metrics-only`), in the metrics' own units: the heat maps only.

Figures written into --out-dir: gap_heatmaps.png (1500 x 1300 px), and from a report also
gap_effects.png (1300 x 700 px) and gap_before_after.png (1400 x 650 px).

What is read from gap.json:
  metrics[]        name, unit (the rows of the heat maps, in this order);
  cells[]          light, preset, distance_m, angle_deg, real {metric: v}, sim {metric: v},
                   z_baseline, z_heldout {metric: z}, significant_after;
  effects[]        name, scope, params, ci95, delta_bic, earns, shrink_in_sample_pct,
                   shrink_heldout_pct (best first);
  selected[]       name; confounded[] effects [a, b], correlation;
  how_far          baseline, calibrated, selected_in_sample, selected_heldout: overall and
                   per_metric gap (mean z^2); shrink_in_sample_pct, shrink_heldout_pct.
A report without one of these parts is refused with one line naming the part.

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
# Metrics of the CSV fallback: label, unit, real - sim of one matched pair of rows.
CSV_METRICS = [
    ("median bias", "m", lambda r, s: r["median_m"] - s["median_m"]),
    ("mean - median", "m", lambda r, s: (r["mean_m"] - r["median_m"]) -
     (s["mean_m"] - s["median_m"])),
    ("plane_std", "m", lambda r, s: r["plane_std_m"] - s["plane_std_m"]),
    ("valid_pct", "points", lambda r, s: r["valid_pct"] - s["valid_pct"]),
]
# The stages of the gap in how_far, drawn left to right.
STAGES = [("baseline", "baseline (configured sensor)", "0.55"),
          ("calibrated", "calibrated base", "0.75"),
          ("selected_in_sample", "selected effects, in sample", "tab:cyan"),
          ("selected_heldout", "selected effects, held-out cells", "tab:blue")]


def is_number(v):
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


# --- reading a report ---------------------------------------------------------------------------

def need(obj, key, kind, path, where):
    v = obj.get(key) if isinstance(obj, dict) else None
    if not (is_number(v) if kind is float else isinstance(v, kind)):
        what = {list: "a list", dict: "an object", str: "a string"}.get(kind, "a number")
        raise pc.InputError(f"{path}: {where}{key} is missing or not {what}")
    return v


def read_report(path):
    if not os.path.isfile(path):
        raise pc.InputError(f"{path}: no such file")
    with open(path) as f:
        try:
            doc = json.load(f)
        except json.JSONDecodeError as e:
            raise pc.InputError(f"{path}: not JSON ({e.msg}, line {e.lineno})")
        except UnicodeDecodeError:
            raise pc.InputError(f"{path}: not text")
    if not isinstance(doc, dict):
        raise pc.InputError(f"{path}: not a gap report (a JSON object expected)")
    for key in ("metrics", "cells", "effects", "selected", "confounded"):
        need(doc, key, list, path, "")
    need(doc, "how_far", dict, path, "")
    return doc


def metric_units(doc, path):
    out = {}
    for i, m in enumerate(doc["metrics"]):
        out[need(m, "name", str, path, f"metrics[{i}].")] = str(m.get("unit", ""))
    if not out:
        raise pc.InputError(f"{path}: metrics is empty")
    return out


def cell_values(doc, path):
    """[(cell, metric, real - sim, held-out z or None, significant after)] from cells[]."""
    units = metric_units(doc, path)
    out = []
    for i, row in enumerate(doc["cells"]):
        where = f"cells[{i}]."
        cell = (need(row, "light", str, path, where), need(row, "preset", str, path, where),
                need(row, "distance_m", float, path, where),
                need(row, "angle_deg", float, path, where))
        real = need(row, "real", dict, path, where)
        sim = need(row, "sim", dict, path, where)
        zh = row.get("z_heldout") if isinstance(row.get("z_heldout"), dict) else {}
        for metric in units:
            r, s = real.get(metric), sim.get(metric)
            if is_number(r) and is_number(s):
                z = zh.get(metric)
                out.append((cell, metric, float(r) - float(s), float(z) if is_number(z) else None,
                            bool(row.get("significant_after", True))))
    if not out:
        raise pc.InputError(f"{path}: no cell has both a real and a simulated value")
    return out, units


# --- the CSV fallback ---------------------------------------------------------------------------

def csv_values(real_path, sim_path):
    need_cols = ["light", "emitter", "preset", "distance_m", "angle_deg", "mean_m", "median_m",
                 "plane_std_m", "valid_pct"]

    def table(path):
        out = {}
        for r in pc.ok_rows(pc.read_csv(path, need_cols)):
            key = (r["light"], r["preset"], r["emitter"], pc.number(r, "distance_m", path),
                   pc.number(r, "angle_deg", path))
            out[key] = {c: pc.number(r, c, path) for c in need_cols[5:]}
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
                           None, True))
    return values, len(common), len(real), len(sim)


# --- figures ------------------------------------------------------------------------------------

def mean_by_cell(values):
    """{metric: {cell: (mean real - sim, explained)}} over the emitter rows of a cell; explained:
    no row of the cell is significant any more after the selected effects."""
    acc = {}
    for cell, metric, gap, _, significant in values:
        d = acc.setdefault(metric, {}).setdefault(cell, [[], False])
        d[0].append(gap)
        d[1] = d[1] or significant
    return {m: {c: (sum(v[0]) / len(v[0]), not v[1]) for c, v in cells.items()}
            for m, cells in acc.items()}


def heatmaps(values, out, title, note, labels=None):
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
        label = (labels or {}).get(metric, metric)
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
            digits = 0 if vmax >= 10 else 1 if vmax >= 2 else 2
            for ai, a in enumerate(angs):
                for di, d in enumerate(dists):
                    if (d, a) not in mine:
                        continue
                    v, explained = mine[(d, a)]
                    text = f"{v:+.{digits}f}"
                    if float(text) == 0:
                        text = f"{0:.{digits}f}"  # no "-0.0"
                    ax.text(di, ai, text + (" ✓" if explained else ""), ha="center",
                            va="center", fontsize=9,
                            color="white" if abs(v) > 0.6 * vmax else "black")
            ax.set_xticks(range(len(dists)), [f"{d:g}" for d in dists])
            ax.set_yticks(range(len(angs)), [f"{a:g}°" for a in angs])
            if i == 0:
                ax.set_title(pc.scenario_title(light, preset), fontsize=11)
            if i == len(metrics) - 1:
                ax.set_xlabel("distance [m]")
            if j == 0:
                ax.set_ylabel(f"{label}\noff-axis angle")
        fig.colorbar(image, ax=axes[i, :], shrink=0.9, label=f"real − sim, {label}")
    fig.suptitle(title + "\n" + note, fontsize=13)
    pc.save(fig, out)


def params_text(effect):
    """'p = v [lo, hi]' of a shared effect; 'per light' or 'per scenario' otherwise (the report
    has them)."""
    params, ci = effect.get("params"), effect.get("ci95")
    if not isinstance(params, dict) or not params:
        return ""
    if effect.get("scope") in ("per_light", "per_scenario"):
        return effect["scope"].replace("_", " ") + " (values in report.md)"
    parts = []
    for p, v in params.items():
        if not is_number(v):
            continue
        text = f"{p} = {v:.3g}"
        band = ci.get(p) if isinstance(ci, dict) else None
        if isinstance(band, list) and len(band) == 2 and all(is_number(b) for b in band):
            text += f" [{band[0]:.3g}, {band[1]:.3g}]"
        parts.append(text)
    return "; ".join(parts)


def effects_figure(doc, out):
    effects = [e for e in doc["effects"] if isinstance(e, dict) and isinstance(e.get("name"), str)]
    selected = [s["name"] for s in doc["selected"] if isinstance(s, dict) and "name" in s]
    partners = {}
    for c in doc["confounded"]:
        pair = c.get("effects") if isinstance(c, dict) else None
        if isinstance(pair, list) and len(pair) == 2:
            r = c.get("correlation")
            for a, b in (pair, pair[::-1]):
                partners.setdefault(str(a), []).append(
                    f"{b} (r = {r:.2f})" if is_number(r) else str(b))
    fig, (ax, axb) = pc.plt.subplots(1, 2, figsize=EFFECTS_FIGSIZE, sharey=True,
                                     width_ratios=[2.4, 1], layout="constrained")
    if not effects:
        ax.text(0.5, 0.5, "no candidate effect was fitted", ha="center", transform=ax.transAxes)
        fig.suptitle("Candidate effects")
        pc.save(fig, out)
        return
    ys = list(range(len(effects)))[::-1]  # best first, at the top
    held = [e.get("shrink_heldout_pct") for e in effects]
    ins = [e.get("shrink_in_sample_pct") for e in effects]
    h = 0.38
    ax.barh([y + h / 2 for y in ys], [v if is_number(v) else 0 for v in ins], height=h,
            color="0.75", label="in sample")
    ax.barh([y - h / 2 for y in ys], [v if is_number(v) else 0 for v in held], height=h,
            color="tab:blue", label="held-out cells (no part in the fit)")
    labels = []
    for e in effects:
        name = e["name"] + (" ★" if e["name"] in selected else "")
        lines = [name]
        if e["name"] in partners:
            lines.append("≈ " + ", ".join(partners[e["name"]]))
        text = params_text(e)
        if text:
            lines.append(text)
        labels.append("\n".join(lines))
    ax.set_yticks(ys, labels, fontsize=8.5)
    for y, v in zip(ys, held):
        if is_number(v):
            ax.text(v, y - h / 2, f" {v:.0f} %" if v >= 0 else f"{v:.0f} % ", va="center",
                    ha="left" if v >= 0 else "right", fontsize=8.5)
    ax.axvline(0, color="k", lw=0.8)
    ax.set_xlabel("share of the baseline gap removed [%]")
    ax.legend(loc="lower right", fontsize=9)
    ax.grid(axis="x", alpha=0.3)
    bic = [e.get("delta_bic") for e in effects]
    earns = [bool(e.get("earns")) for e in effects]
    axb.barh(ys, [b if is_number(b) else 0 for b in bic],
             color=["tab:green" if ok else "0.6" for ok in earns])
    for y, b in zip(ys, bic):
        if is_number(b):
            axb.text(b, y, f" {b:.1f}" if b >= 0 else f"{b:.1f} ", va="center",
                     ha="left" if b >= 0 else "right", fontsize=8.5)
    lo = min([b for b in bic if is_number(b)] + [0.0])
    hi = max([b for b in bic if is_number(b)] + [1.0])
    axb.set_xlim(lo - 0.25 * (hi - lo), hi + 0.25 * (hi - lo))
    axb.axvline(0, color="k", lw=0.8)
    axb.set_xlabel("ΔBIC (> 0: worth its parameters)\ngreen: earns ΔBIC and held-out gain")
    axb.grid(axis="x", alpha=0.3)
    fig.suptitle("Which effect: every candidate fitted alone, best first "
                 "(★ selected; ≈ confounded on this design, not told apart)", fontsize=12)
    pc.save(fig, out)


def before_after_figure(doc, out, path):
    how = doc["how_far"]
    units = metric_units(doc, path)
    groups = ["overall"] + list(units)
    fig, (ax, axs) = pc.plt.subplots(1, 2, figsize=BEFORE_AFTER_FIGSIZE, layout="constrained",
                                     width_ratios=[1.3, 1])
    stages = [s for s in STAGES if isinstance(how.get(s[0]), dict)]
    if not stages:
        raise pc.InputError(f"{path}: how_far has none of "
                            + ", ".join(s[0] for s in STAGES))
    w = 0.8 / len(stages)
    for k, (key, label, color) in enumerate(stages):
        per = how[key].get("per_metric") or {}
        vals = [how[key].get("overall") if g == "overall" else per.get(g) for g in groups]
        xs = [x - 0.4 + w * (k + 0.5) for x in range(len(groups))]
        ax.bar(xs, [v if is_number(v) else float("nan") for v in vals], width=w, color=color,
               label=label)
        if key == "selected_heldout":
            base = how.get("baseline", {})
            bper = base.get("per_metric") or {}
            for x, g, v in zip(xs, groups, vals):
                b = base.get("overall") if g == "overall" else bper.get(g)
                if is_number(v) and is_number(b) and b > 0:
                    ax.text(x, v, f"{100 * (v / b - 1):+.0f}%", ha="center", va="bottom",
                            fontsize=8.5)
    ax.set_yscale("log")
    ax.axhline(1.0, color="k", lw=0.8, ls="--")
    ax.text(len(groups) - 0.5, 1.05, "1 = the camera's repeatability", ha="right",
            va="bottom", fontsize=8.5)
    ax.set_xticks(range(len(groups)), ["all metrics"] + list(units), rotation=12)
    ax.set_ylabel("gap: mean z² (z = (real − sim) / noise)")
    ax.legend(fontsize=8.5, loc="upper right")
    ax.grid(axis="y", alpha=0.3, which="both")
    ax.set_title("Whole gap, per metric (% change held out)")
    before, after, scen = [], [], []
    for row in doc["cells"]:
        zb, zh = row.get("z_baseline"), row.get("z_heldout")
        if not (isinstance(zb, dict) and isinstance(zh, dict)):
            continue
        b = [zb[m] for m in units if is_number(zb.get(m))]
        a = [zh[m] for m in units if is_number(zh.get(m))]
        if b and a:
            before.append(sum(v * v for v in b) / len(b))
            after.append(sum(v * v for v in a) / len(a))
            scen.append((str(row.get("light")), str(row.get("preset"))))
    if before:
        colors = pc.plt.get_cmap("tab10")
        order = sorted(set(scen), key=lambda s: pc.scenario_key(*s))
        for i, s in enumerate(order):
            pts = [(b, a) for b, a, c in zip(before, after, scen) if c == s]
            axs.scatter([p[0] for p in pts], [p[1] for p in pts], s=22, color=colors(i),
                        label=pc.scenario_title(*s), alpha=0.8)
        lo = max(min(before + after), 1e-2) / 1.5
        hi = max(before + after) * 1.5
        axs.plot([lo, hi], [lo, hi], "k", lw=0.8, label="no change")
        axs.set_xscale("log")
        axs.set_yscale("log")
        axs.set_xlim(lo, hi)
        axs.set_ylim(lo, hi)
        axs.set_xlabel("before: mean z² of the recording, configured sensor")
        axs.set_ylabel("after: mean z², selected effects, held out")
        axs.legend(fontsize=8.5, loc="upper left")
        axs.grid(alpha=0.3, which="both")
    else:
        axs.text(0.5, 0.5, "no cell has z_baseline and z_heldout", ha="center",
                 transform=axs.transAxes)
    axs.set_title("Per recording: below the diagonal, the gap shrank")
    sel = ", ".join(s["name"] for s in doc["selected"] if isinstance(s, dict) and "name" in s)
    shrink = how.get("shrink_heldout_pct")
    fig.suptitle("How far the gap shrinks with the selected effects (" + (sel or "none selected")
                 + (f"): {shrink:.1f} % held out" if is_number(shrink) else ")"), fontsize=12)
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
        values, units = cell_values(doc, args.gap)
        labels = {m: f"{m} [{u}]" if u else m for m, u in units.items()}
        n = len(doc["cells"])
        heatmaps(values, heat, f"Where the simulator departs from the camera: real − sim per "
                 f"cell ({os.path.basename(args.gap)}, {n} recordings)",
                 "mean over a cell's emitter rows; ✓ no longer significant once the selected "
                 "effects are added (held out)", labels)
        effects_figure(doc, os.path.join(args.out_dir, "gap_effects.png"))
        before_after_figure(doc, os.path.join(args.out_dir, "gap_before_after.png"), args.gap)
        return
    if not (args.real and args.sim):
        raise pc.InputError("give --gap gap.json, or both --real and --sim")
    values, n, nr, ns = csv_values(args.real, args.sim)
    heatmaps(values, heat, "Where the simulator departs from the camera: real − sim per cell "
             f"({os.path.basename(args.real)} − {os.path.basename(args.sim)})",
             f"metrics' own units; mean over emitter rows; {n} matched rows of {nr} real, "
             f"{ns} simulated")


if __name__ == "__main__":
    pc.run_main(sys.argv[0], main)
