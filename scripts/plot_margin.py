#!/usr/bin/env python3
"""The safety margin of a fitted model over depth x off-axis angle, one column per scenario
(light x preset): its predictive standard deviation (top row) and the safe distance
corrected - k sigma (bottom row), both from the real correct_depth on a grid of measured depth
Z (the model's input) x angle.

sigma = sqrt(g' Cov g + s^2) (lib/model/README.md): the parameters' uncertainty where the
design is thin plus the scatter the model does not explain. On the bottom row each measurement
(--data) sits at its (Z, angle): a circle if its true distance is at or beyond its safe
distance (covered), a red cross if the target was nearer than the safe distance (a miss); the
count is in the title. The dashed outline is the measurements' convex hull.

Usage: plot_margin.py --weights weights.yaml --data metrics.csv --out fig.png
                      [--bin build/apps] [--k 2]
Output: a 1600 x 900 px PNG.
"""
import argparse
import math
import sys

import plot_common as pc

FIGSIZE = (16, 9)


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--weights", required=True, help="a weights YAML (fit_bias --out)")
    ap.add_argument("--data", required=True, help="the metrics CSV the model was fitted to")
    ap.add_argument("--out", required=True)
    ap.add_argument("--bin", default=pc.DEFAULT_BIN, help="folder of correct_depth")
    ap.add_argument("--k", type=float, default=2.0, help="safe distance = corrected - k sigma")
    pc.add_grid_arguments(ap)
    args = ap.parse_args()
    pc.check_grid(args)
    if args.k <= 0:
        raise pc.InputError(f"--k {args.k}: must be > 0")
    weights = pc.read_weights(args.weights)
    rows = pc.ok_rows(pc.read_csv(args.data, ["light", "preset", "distance_m", "angle_deg",
                                              "median_m"]))
    scen = [s for s in pc.scenarios(rows) if s in weights["by_scenario"]][:4]
    if not scen:
        raise pc.InputError(f"{args.weights}: no group matches a scenario of {args.data}")
    z = [pc.number(r, "median_m", args.data) for r in rows]
    depths = pc.linspace(max(0.5, min(z) - 0.5), max(z) + 0.5, args.grid[0])
    angles = pc.linspace(0.0, args.max_angle, args.grid[1])
    grid = pc.evaluate_grid(args.bin, args.weights, scen, depths, angles, args.k)
    corrected = pc.correct(args.bin, args.weights, args.data, args.k)

    std_max = max(max(max(line) for line in grid[s]["std"]) for s in scen)
    std_step = 0.05 if std_max <= 1.5 else 0.1
    std_levels = [i * std_step for i in range(int(std_max / std_step) + 2)]
    safe_all = [v for s in scen for line in grid[s]["safe"] for v in line]
    safe_levels = list(range(int(math.floor(min(safe_all))), int(math.ceil(max(safe_all))) + 1))
    fig, axes = pc.plt.subplots(2, len(scen), figsize=FIGSIZE, sharex=True, sharey=True,
                                squeeze=False, layout="constrained")
    for col, (light, preset) in enumerate(scen):
        maps = grid[(light, preset)]
        top, bottom = axes[0][col], axes[1][col]
        f_std = top.contourf(depths, angles, maps["std"], levels=std_levels, cmap="magma_r")
        c = top.contour(depths, angles, maps["std"], levels=8, colors="k", linewidths=0.5)
        top.clabel(c, fmt="%.2f", fontsize=8)
        f_safe = bottom.contourf(depths, angles, maps["safe"], levels=safe_levels,
                                 cmap="viridis")
        c = bottom.contour(depths, angles, maps["safe"], levels=list(range(0, 40, 2)),
                           colors="w", linewidths=0.7)
        bottom.clabel(c, fmt="%d m", fontsize=8)
        sel = [r for r in corrected if r.get("status", "ok") in ("", "ok") and
               r["light"] == light and r["preset"] == preset]
        pts = [(float(r["median_m"]), float(r["angle_deg"]),
                float(r["distance_m"]) >= float(r["margin_m"])) for r in sel]
        outline = pc.hull([(p[0], p[1]) for p in pts])
        for ax in (top, bottom):
            ax.plot([p[0] for p in outline], [p[1] for p in outline], "k--", lw=1.0)
        ok = [p for p in pts if p[2]]
        miss = [p for p in pts if not p[2]]
        bottom.scatter([p[0] for p in ok], [p[1] for p in ok], facecolors="white",
                       edgecolors="k", s=30, zorder=3, clip_on=False, label="truth beyond safe")
        bottom.scatter([p[0] for p in miss], [p[1] for p in miss], color="red", marker="X",
                       s=90, edgecolors="k", zorder=4, clip_on=False,
                       label="truth nearer than safe (miss)")
        top.set_title(f"{light}/{preset}: predictive σ")
        bottom.set_title(f"{light}/{preset}: safe distance ({len(ok)}/{len(pts)} covered)",
                         fontsize=11)
        bottom.set_xlabel("measured depth Z [m]")
    axes[0][0].set_ylabel("off-axis angle α [°]")
    axes[1][0].set_ylabel("off-axis angle α [°]")
    fig.colorbar(f_std, ax=axes[0, :], label="predictive σ [m]", shrink=0.9,
                 ticks=std_levels[::2])
    fig.colorbar(f_safe, ax=axes[1, :], label=f"safe distance = corrected - {args.k:g}σ [m]",
                 shrink=0.9, ticks=safe_levels[::2])
    handles, names = axes[1][0].get_legend_handles_labels()
    Line2D = pc.matplotlib.lines.Line2D
    handles.append(Line2D([], [], color="k", ls="--", lw=1.0))
    names.append("hull of the measurements")
    fig.legend(handles, names, loc="outside lower center", ncol=3)
    fig.suptitle(f"Safety margin of {pc.model_label(weights)}: predictive σ and safe distance "
                 f"(k = {args.k:g})")
    pc.save(fig, args.out)


if __name__ == "__main__":
    pc.run_main(sys.argv[0], main)
