#!/usr/bin/env python3
"""Depth error against distance, one line per off-axis angle, one panel per scenario
(light x preset): the article's Figure 4.

error = median_m - distance_m (the article's definition: the measured median depth Z minus the
nominal distance, a range; at 35 deg it includes the projection -D(1 - cos 35) = -0.18 D).
Emitter off: solid line, circles; emitter on: dashed line, triangles (shifted 0.15 m right so
both stay visible). Rows whose status is not ok are left out and counted in the title.

Usage: plot_error_vs_distance.py --in metrics.csv --out fig.png [--title TEXT]
Input: any panel-metrics CSV (the article's table, panel_extract's or simulate's output).
Output: a 1200 x 900 px PNG.
"""
import argparse
import sys

import plot_common as pc

FIGSIZE = (12, 9)


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--in", dest="path", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--title", default="Depth error against distance (median depth - nominal "
                                        "distance)")
    args = ap.parse_args()
    rows = pc.read_csv(args.path, ["light", "emitter", "preset", "distance_m", "angle_deg",
                                   "median_m"])
    good = pc.ok_rows(rows)
    if not good:
        raise pc.InputError(f"{args.path}: no row with status ok")
    scen = pc.scenarios(good)
    angles = sorted({pc.number(r, "angle_deg", args.path) for r in good})
    colors = pc.plt.cm.viridis([i / max(1, len(angles) - 1) * 0.9 for i in range(len(angles))])

    ncols = 2 if len(scen) > 1 else 1
    nrows = (len(scen) + ncols - 1) // ncols
    fig, axes = pc.plt.subplots(nrows, ncols, figsize=FIGSIZE, sharex=True, sharey=True,
                                squeeze=False, layout="constrained")
    for ax, (light, preset) in zip(axes.flat, scen):
        ax.axhline(0, color="0.3", lw=0.8)
        for ai, a in enumerate(angles):
            for emitter, style, marker, shift in (("off", "-", "o", 0.0), ("on", "--", "^", 0.15)):
                pts = sorted((pc.number(r, "distance_m", args.path),
                              pc.number(r, "median_m", args.path) -
                              pc.number(r, "distance_m", args.path))
                             for r in good if r["light"] == light and r["preset"] == preset and
                             r["emitter"] == emitter and pc.number(r, "angle_deg") == a)
                if not pts:
                    continue
                ax.plot([p[0] + shift for p in pts], [p[1] for p in pts], linestyle=style,
                        marker=marker, color=colors[ai], ms=6, lw=1.5)
        ax.set_title(pc.scenario_title(light, preset))
        ax.grid(alpha=0.3)
    for ax in axes.flat[len(scen):]:
        ax.set_visible(False)
    for ax in axes[-1]:
        ax.set_xlabel("nominal distance D [m]")
    for ax in axes[:, 0]:
        ax.set_ylabel("error Z - D [m]")
    Line2D = pc.matplotlib.lines.Line2D
    handles = [Line2D([], [], color=colors[i], lw=3, label=f"{a:g}°") for i, a in
               enumerate(angles)]
    handles += [Line2D([], [], color="0.3", ls="-", marker="o", label="emitter off"),
                Line2D([], [], color="0.3", ls="--", marker="^", label="emitter on")]
    fig.legend(handles=handles, loc="outside lower center", ncol=len(handles),
               title="off-axis angle (colour) and emitter (line)")
    skipped = len(rows) - len(good)
    title = args.title + (f"  ({skipped} rows not ok, left out)" if skipped else "")
    fig.suptitle(title)
    pc.save(fig, args.out)


if __name__ == "__main__":
    pc.run_main(sys.argv[0], main)
