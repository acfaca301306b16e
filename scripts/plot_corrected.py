#!/usr/bin/env python3
"""Raw and corrected distances against the truth, with the safe distances, one column per
scenario (light x preset): the article's Figure 6.

Top row: the distances themselves against the nominal distance D (the truth; the diagonal is a
perfect reading). Bottom row: their errors (distance - D). Series:
  raw      the measured median depth Z (grey circles);
  each model's corrected distance (correct_depth's corrected_m, in-sample: the model saw the row);
  held out (with --cv): the corrected distance from the fit that did not see the row's test
           point (fit_bias --cv-out, scheme 'point': D - heldout_error_m), hollow markers;
  safe     the first model's safe distance, corrected - k sigma (correct_depth's margin_m),
           orange triangles: a distance the target is not nearer than. Its coverage, the share of
           truths at or beyond it, is printed in the panel.
Series are shifted a little sideways at each distance so they stay apart.

Usage: plot_corrected.py --corrected default.csv --label "disp_knots" [--cv cv_default.csv]
                         [--corrected paper6.csv --label "eq. 6" [--cv cv_paper6.csv]] --out fig.png
(--cv for all models or none, in the same order.)
Output: a 1600 x 950 px PNG.
"""
import argparse
import math
import sys

import plot_common as pc

FIGSIZE = (16, 9.5)
ERROR_LIMIT_M = 4.0  # the error row's half-range; errors beyond it sit on its edge, labelled
MODEL_COLORS = ["tab:blue", "tab:green", "tab:purple"]
MODEL_MARKERS = ["s", "D", "P"]


def rms(values):
    return math.sqrt(sum(v * v for v in values) / len(values)) if values else float("nan")


def read_heldout(path):
    """{bag: held-out corrected distance - truth} from fit_bias --cv-out, scheme 'point'."""
    rows = pc.read_csv(path, ["bag", "scheme", "heldout_error_m"])
    out = {}
    for r in rows:
        if r["scheme"] == "point" and r["heldout_error_m"] not in ("", "nan"):
            out[r["bag"]] = -pc.number(r, "heldout_error_m", path)  # error = predicted - target
    if not out:
        raise pc.InputError(f"{path}: no row of scheme 'point' (fit_bias --cv point)")
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--corrected", action="append", required=True,
                    help="correct_depth's output; once per model, the first gives the safe "
                         "distances")
    ap.add_argument("--label", action="append", help="a model's name, in --corrected's order")
    ap.add_argument("--cv", action="append", help="fit_bias --cv-out of each model, same order")
    ap.add_argument("--out", required=True)
    ap.add_argument("--k", type=float, default=2.0, help="the k of correct_depth --k (label)")
    args = ap.parse_args()
    labels = args.label or []
    if len(labels) != len(args.corrected):
        labels = [f"model {i + 1}" for i in range(len(args.corrected))]
    if args.cv and len(args.cv) != len(args.corrected):
        raise pc.InputError(f"--cv given {len(args.cv)} times for {len(args.corrected)} "
                            "--corrected: give it for every model or none")
    need = ["bag", "light", "preset", "distance_m", "median_m", "corrected_m", "margin_m"]
    models = []
    for i, path in enumerate(args.corrected):
        rows = pc.ok_rows(pc.read_csv(path, need))
        heldout = read_heldout(args.cv[i]) if args.cv else None
        models.append((labels[i], path, rows, heldout))
    base_path, base_rows = models[0][1], models[0][2]
    scen = pc.scenarios(base_rows)[:4]

    fig, axes = pc.plt.subplots(2, len(scen), figsize=FIGSIZE, sharex=True, sharey="row",
                                squeeze=False, layout="constrained")
    nseries = 2 + len(models) * (2 if args.cv else 1)
    step = 0.22

    def shift(i):
        return (i - (nseries - 1) / 2) * step

    for col, (light, preset) in enumerate(scen):
        top, bottom = axes[0][col], axes[1][col]
        lines = []
        clipped = []

        def plot(i, truths, values, label, **style):
            xs = [t + shift(i) for t in truths]
            top.scatter(xs, values, label=label, s=26, **style)
            errs = [v - t for v, t in zip(values, truths)]
            shown = [max(-ERROR_LIMIT_M, min(ERROR_LIMIT_M, e)) for e in errs]
            bottom.scatter(xs, shown, s=26, **style)
            clipped.extend(e for e, v in zip(errs, shown) if e != v)
            return errs

        sel = [r for r in base_rows if r["light"] == light and r["preset"] == preset]
        truth = [pc.number(r, "distance_m", base_path) for r in sel]
        raw = [pc.number(r, "median_m", base_path) for r in sel]
        e = plot(0, truth, raw, "raw Z", color="0.45", marker="o")
        lines.append(f"raw RMSE {rms(e):.2f} m")
        series = 1
        for m, (label, path, rows, heldout) in enumerate(models):
            msel = [r for r in rows if r["light"] == light and r["preset"] == preset]
            t = [pc.number(r, "distance_m", path) for r in msel]
            c = [pc.number(r, "corrected_m", path) for r in msel]
            e = plot(series, t, c, f"{label}: corrected", color=MODEL_COLORS[m % 3],
                     marker=MODEL_MARKERS[m % 3])
            series += 1
            lines.append(f"{label}: in-sample {rms(e):.2f} m")
            if heldout is not None:
                pairs = [(pc.number(r, "distance_m", path), heldout[r["bag"]])
                         for r in msel if r["bag"] in heldout]
                plot(series, [p[0] for p in pairs], [p[0] + p[1] for p in pairs],
                     f"{label}: held out (LOTPO)", facecolors="none",
                     edgecolors=MODEL_COLORS[m % 3], marker=MODEL_MARKERS[m % 3], linewidths=1.2)
                series += 1
                lines.append(f"{label}: held out {rms([p[1] for p in pairs]):.2f} m")
        safe = [pc.number(r, "margin_m", base_path) for r in sel]
        plot(series, truth, safe, f"{models[0][0]}: safe distance (corrected - {args.k:g}σ)",
             color="tab:orange", marker="v")
        covered = sum(1 for s, t in zip(safe, truth) if t >= s)
        lines.append(f"safe: truth beyond it in {covered}/{len(truth)}")
        lo = min(truth) - 1.5
        hi = max(truth) + 1.5
        top.plot([lo, hi], [lo, hi], color="k", lw=0.8, zorder=0)
        bottom.axhline(0, color="k", lw=0.8, zorder=0)
        top.set_title(pc.scenario_title(light, preset))
        if clipped:
            bottom.text(0.97, 0.97, "off scale (on the edge): " +
                        ", ".join(f"{e:+.1f}" for e in sorted(clipped)) + " m",
                        transform=bottom.transAxes, fontsize=8.5, va="top", ha="right",
                        bbox=dict(facecolor="white", alpha=0.85, lw=0))
        top.text(0.03, 0.97, "\n".join(lines), transform=top.transAxes, fontsize=8.5,
                 va="top", ha="left", bbox=dict(facecolor="white", alpha=0.85, lw=0))
        for ax in (top, bottom):
            ax.grid(alpha=0.3)
        bottom.set_xlabel("true (nominal) distance D [m]")
        bottom.set_ylim(-ERROR_LIMIT_M * 1.05, ERROR_LIMIT_M * 1.05)
        bottom.set_xticks(sorted(set(truth)))
    axes[0][0].set_ylabel("distance [m]")
    axes[1][0].set_ylabel(f"distance - D [m]  (+: too far; clipped at ±{ERROR_LIMIT_M:g})")
    handles, names = axes[0][0].get_legend_handles_labels()
    fig.legend(handles, names, loc="outside lower center", ncol=len(names))
    fig.suptitle("Raw and corrected distances against the truth, with safe distances "
                 "(RMSE of distance - D per series)")
    pc.save(fig, args.out)


if __name__ == "__main__":
    pc.run_main(sys.argv[0], main)
