#!/usr/bin/env python3
"""Iso-error contours of fitted bias models over depth x off-axis angle, one row per scenario
(light x preset), one column per model (e.g. the article's eq. 6 and our default, side by
side): the article's Figure 5.

The map is the model's predicted bias b(Z, alpha) = Z - D (the measured median depth minus the
distance the model corrects it to), evaluated by the real correct_depth on a grid of measured
depth Z (the model's input) x off-axis angle. On the optical axis Z is the distance.

Safety-critical zone (hatched, bold outline): b > +THRESHOLD (default 0.5 m), where the raw
reading puts an obstacle more than THRESHOLD farther than it is: over-estimating a distance is
the dangerous direction (DESIGN.md, "Safety margins"). The dotted line is b = -THRESHOLD (the
reading is that much too near: safe, but costly). Markers: the measurements (--data), coloured
by their own error on the same scale; the dashed outline is their convex hull: outside it the
model extrapolates.

Usage: plot_iso_error.py --weights paper6.yaml --weights default.yaml --data metrics.csv
                         --out fig.png [--bin build/apps] [--threshold 0.5]
Output: an 1100 x 1500 px PNG (any number of models side by side, at most four scenarios
shown in the table's order).
"""
import argparse
import sys

import plot_common as pc

FIGSIZE = (11, 15)
LEVELS = [x * 0.25 for x in range(-12, 13)]  # -3 ... 3 m
LINE_LEVELS = [x * 0.5 for x in range(-6, 7)]


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--weights", action="append", required=True,
                    help="a weights YAML (fit_bias --out); give it once per model")
    ap.add_argument("--data", required=True, help="the metrics CSV the models were fitted to")
    ap.add_argument("--out", required=True)
    ap.add_argument("--bin", default=pc.DEFAULT_BIN, help="folder of correct_depth")
    ap.add_argument("--threshold", type=float, default=0.5,
                    help="bias [m] beyond which a reading is safety-critical")
    ap.add_argument("--depth-range", type=float, nargs=2, metavar=("MIN_M", "MAX_M"),
                    help="measured depths of the grid (default: the data's, 0.5 m wider)")
    pc.add_grid_arguments(ap)
    args = ap.parse_args()
    pc.check_grid(args)
    if args.threshold <= 0:
        raise pc.InputError(f"--threshold {args.threshold}: must be > 0")

    rows = pc.ok_rows(pc.read_csv(args.data, ["light", "preset", "distance_m", "angle_deg",
                                              "median_m"]))
    scen = pc.scenarios(rows)[:4]
    if args.depth_range:
        lo, hi = args.depth_range
    else:
        z = [pc.number(r, "median_m", args.data) for r in rows]
        lo, hi = max(0.5, min(z) - 0.5), max(z) + 0.5
    if not 0 < lo < hi:
        raise pc.InputError(f"--depth-range {lo} {hi}: need 0 < MIN_M < MAX_M")
    depths = pc.linspace(lo, hi, args.grid[0])
    angles = pc.linspace(0.0, args.max_angle, args.grid[1])
    models = []
    for path in args.weights:
        weights = pc.read_weights(path)
        missing = [s for s in scen if s not in weights["by_scenario"]]
        if missing:
            raise pc.InputError(f"{path}: no group for {missing[0][0]}/{missing[0][1]}")
        models.append((pc.model_label(weights),
                       pc.evaluate_grid(args.bin, path, scen, depths, angles)))

    fig, axes = pc.plt.subplots(len(scen), len(models), figsize=FIGSIZE, sharex=True,
                                sharey=True, squeeze=False, layout="constrained")
    cmap = pc.plt.get_cmap("RdBu_r")
    filled = None
    for i, (light, preset) in enumerate(scen):
        data = [(pc.number(r, "median_m", args.data), pc.number(r, "angle_deg", args.data),
                 pc.number(r, "median_m", args.data) - pc.number(r, "distance_m", args.data))
                for r in rows if r["light"] == light and r["preset"] == preset]
        outline = pc.hull([(z, a) for z, a, _ in data])
        for j, (label, grid) in enumerate(models):
            ax = axes[i][j]
            bias = grid[(light, preset)]["bias"]
            filled = ax.contourf(depths, angles, bias, levels=LEVELS, cmap=cmap, extend="both")
            lines = ax.contour(depths, angles, bias, levels=LINE_LEVELS, colors="k",
                               linewidths=0.5, alpha=0.6)
            ax.clabel(lines, fmt="%+.1f", fontsize=8)
            # Safety-critical zone: b > +threshold, hatched with a bold outline.
            ax.contourf(depths, angles, bias, levels=[args.threshold, 1e9], colors="none",
                        hatches=["///"])
            ax.contour(depths, angles, bias, levels=[args.threshold], colors="k",
                       linewidths=2.2)
            ax.contour(depths, angles, bias, levels=[-args.threshold], colors="k",
                       linewidths=1.4, linestyles=":")
            ax.plot([p[0] for p in outline], [p[1] for p in outline], "k--", lw=1.0)
            ax.scatter([d[0] for d in data], [d[1] for d in data], c=[d[2] for d in data],
                       cmap=cmap, vmin=LEVELS[0], vmax=LEVELS[-1], edgecolors="k", s=36,
                       linewidths=0.8, zorder=3, clip_on=False)
            ax.set_title(f"{light}/{preset}: {label}", fontsize=11)
            if i == len(scen) - 1:
                ax.set_xlabel("measured depth Z [m] (model input)")
            if j == 0:
                ax.set_ylabel("off-axis angle α [°]")
    cbar = fig.colorbar(filled, ax=axes, location="right", shrink=0.5, ticks=LINE_LEVELS)
    cbar.set_label("predicted error b = Z - D [m] (+: reads too far)")
    Patch = pc.matplotlib.patches.Patch
    Line2D = pc.matplotlib.lines.Line2D
    handles = [Patch(facecolor="white", edgecolor="k", hatch="///",
                     label=f"safety-critical: b > +{args.threshold:g} m (obstacle nearer than "
                           "read)"),
               Line2D([], [], color="k", ls=":", lw=1.4, label=f"b = -{args.threshold:g} m"),
               Line2D([], [], color="k", ls="--", lw=1.0, label="hull of the measurements"),
               Line2D([], [], color="w", marker="o", markeredgecolor="k", markerfacecolor="0.6",
                      ms=7, label="measurement (colour: its error)")]
    fig.legend(handles=handles, loc="outside lower center", ncol=2)
    fig.suptitle("Iso-error contours of the fitted bias models")
    pc.save(fig, args.out)


if __name__ == "__main__":
    pc.run_main(sys.argv[0], main)
