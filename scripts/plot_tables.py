#!/usr/bin/env python3
"""The tables that go beside the figures: the article's Table 6 reproduced, and the
cross-validation table of fitted models.

table6.csv / table6.md: our eq. 6 fit (fit_bias --model paper6 --lambda 0.001, per light x
  preset) beside the article's (config/data/paper_table6.csv): w0..w5, in-sample RMSE and MAE,
  ours and the article's, and their difference. The article prints two sunset weights as "-":
  those cells are empty in its CSV and ours stand alone.
cv_table.csv / cv_table.md: per model and scenario, in-sample, leave-one-test-point-out (LOTPO)
  and leave-one-distance-out (LODO) RMSE and MAE, as fit_bias wrote them into the weights YAML,
  with the article's in-sample RMSE for reference.
safety_table.csv / safety_table.md (with --safety): per model and scenario, from correct_depth's
  output and fit_bias --cv-out (scheme 'point'):
  - over-reads: rows whose corrected distance is more than OVER_READ_M (0.5 m) beyond the truth
    (the dangerous direction), in-sample and held out (the fit that did not see the test point);
  - coverage: rows whose truth is at or beyond the safe distance corrected - k sigma, in-sample,
    and held out (the held-out corrected distance minus the same k sigma: sigma from the full
    fit, as correct_depth gives no held-out sigma; an approximation, stated in the table);
  - the mean margin k sigma.

Usage: plot_tables.py --paper6 weights_paper6.yaml --article paper_table6.csv
                      --weights weights.yaml [--weights other.yaml ...]
                      [--safety LABEL corrected.csv cv.csv ...] [--k 2]
                      [--check-table6 TOL] --out-dir DIR
"""
import argparse
import csv
import io
import os
import sys
import tempfile

import plot_common as pc

PAPER6 = ["w0", "w1", "w2", "w3", "w4", "w5"]
OVER_READ_M = 0.5


def write_atomic(path, text):
    folder = os.path.dirname(os.path.abspath(path))
    os.makedirs(folder, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=folder, suffix=".tmp")
    with os.fdopen(fd, "w", newline="") as f:
        f.write(text)
    os.chmod(tmp, 0o666 & ~pc.UMASK)
    os.replace(tmp, path)
    print(f"wrote {path}")


def csv_text(header, rows):
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(header)
    w.writerows(rows)
    return buf.getvalue()


def fmt(v, digits=3):
    if v is None:
        return ""
    r = round(v, digits)
    return f"{(0.0 if r == 0 else r):.{digits}f}"  # no "-0.000"


def table6(paper6_path, article_path, out_dir):
    weights = pc.read_weights(paper6_path)
    if weights.get("model") != "paper6":
        raise pc.InputError(f"{paper6_path}: model is '{weights.get('model')}', not paper6")
    article = pc.read_csv(article_path, ["light", "preset"] + PAPER6 + ["rmse_m", "mae_m"])
    header = ["light", "preset"]
    for name in PAPER6 + ["rmse_m", "mae_m"]:
        header += [f"{name}_ours", f"{name}_article", f"{name}_diff"]
    rows, md = [], []
    md.append(f"Eq. 6 per light × preset, λ = {weights.get('lambda')}: **ours** / article "
              "(article's \"-\": ours alone)")
    md.append("")
    md.append("| scenario | " + " | ".join(PAPER6) + " | RMSE [m] | MAE [m] |")
    md.append("|---" * (len(PAPER6) + 3) + "|")
    worst = 0.0
    for a in article:
        key = (a["light"], a["preset"])
        group = weights["by_scenario"].get(key)
        if group is None:
            raise pc.InputError(f"{paper6_path}: no group {key[0]}/{key[1]} (in {article_path})")
        ours = dict(group["weights"])
        ours["rmse_m"] = group["rmse_m"]
        ours["mae_m"] = group["mae_m"]
        row = [key[0], key[1]]
        cells = []
        for name in PAPER6 + ["rmse_m", "mae_m"]:
            mine = ours.get(name)
            theirs = pc.number(a, name, article_path, default=float("nan"))
            theirs = None if theirs != theirs else theirs
            diff = None if theirs is None or mine is None else mine - theirs
            if diff is not None:
                worst = max(worst, abs(diff))
            row += [fmt(mine), fmt(theirs), fmt(diff)]
            cells.append(f"**{mine:.3f}**" + (f" / {theirs:.3f}" if theirs is not None else
                                               " / -"))
        rows.append(row)
        md.append(f"| {key[0]}/{key[1]} | " + " | ".join(cells) + " |")
    md.append("")
    md.append(f"Largest difference from the article's printed values: {worst:.3f} "
              "(its values have three decimals).")
    write_atomic(os.path.join(out_dir, "table6.csv"), csv_text(header, rows))
    write_atomic(os.path.join(out_dir, "table6.md"), "\n".join(md) + "\n")
    return worst


def cv_entries(group):
    out = {"in": (group.get("rmse_m"), group.get("mae_m"))}
    for cv in [group.get("cv")] + list(group.get("cv_more") or []):
        if isinstance(cv, dict) and cv.get("scheme"):
            out[cv["scheme"]] = (cv.get("rmse_m"), cv.get("mae_m"))
    return out


def cv_table(weight_paths, article_path, out_dir):
    article = {(a["light"], a["preset"]): pc.number(a, "rmse_m", article_path)
               for a in pc.read_csv(article_path, ["light", "preset", "rmse_m"])}
    models = [(pc.read_weights(p), p) for p in weight_paths]
    scen = sorted({k for w, _ in models for k in w["by_scenario"]} | set(article),
                  key=lambda s: pc.scenario_key(*s))
    header = ["model", "loss", "lambda", "light", "preset", "n", "rmse_in_m", "mae_in_m",
              "rmse_lotpo_m", "mae_lotpo_m", "rmse_lodo_m", "mae_lodo_m"]
    rows = []
    md = ["RMSE [m] per scenario: in-sample / LOTPO (leave one test point out: both emitter "
          "rows of a point leave together) / LODO (leave one distance out)", "",
          "| model | " + " | ".join(f"{l}/{p}" for l, p in scen) + " |",
          "|---" * (len(scen) + 1) + "|",
          "| article (eq. 6, in-sample only) | " +
          " | ".join(f"{article[s]:.3f} / – / –" if s in article else "–" for s in scen) +
          " |"]
    for w, _ in models:
        loss = {"none": "squares", None: "?"}.get(w.get("loss"), w.get("loss"))
        label = f"{w.get('model')} ({loss} loss, λ = {w.get('lambda')})"
        cells = []
        for s in scen:
            g = w["by_scenario"].get(s)
            if g is None:
                cells.append("–")
                continue
            e = cv_entries(g)
            get = lambda k, i: e.get(k, (None, None))[i]  # noqa: E731
            rows.append([w.get("model"), w.get("loss"), w.get("lambda"), s[0], s[1], g.get("n"),
                         fmt(get("in", 0)), fmt(get("in", 1)), fmt(get("point", 0)),
                         fmt(get("point", 1)), fmt(get("distance", 0)), fmt(get("distance", 1))])
            cells.append(" / ".join(fmt(get(k, 0)) or "–" for k in ("in", "point", "distance")))
        md.append(f"| {label} | " + " | ".join(cells) + " |")
    write_atomic(os.path.join(out_dir, "cv_table.csv"), csv_text(header, rows))
    write_atomic(os.path.join(out_dir, "cv_table.md"), "\n".join(md) + "\n")


def safety_table(models, k, out_dir):
    header = ["model", "light", "preset", "rows", "over_read_in_sample", "over_read_heldout",
              "covered_in_sample", "covered_heldout", "mean_margin_m"]
    rows = []
    md = [f"Per model and scenario: corrected distance more than {OVER_READ_M:g} m beyond the "
          "truth (over-reads, in-sample / held out); truth at or beyond the safe distance "
          f"corrected - {k:g}σ (coverage, in-sample / held out: held-out corrected distance "
          "minus the full fit's k σ); mean margin k σ [m].", "",
          "| model | scenario | over-reads in / held out | coverage in / held out | "
          "mean kσ [m] |", "|---|---|---|---|---|"]
    for label, corrected_path, cv_path in models:
        corrected = pc.ok_rows(pc.read_csv(corrected_path, ["bag", "light", "preset",
                                                            "distance_m", "corrected_m",
                                                            "predictive_std_m", "margin_m"]))
        heldout = {}
        for r in pc.read_csv(cv_path, ["bag", "scheme", "heldout_error_m"]):
            if r["scheme"] == "point":
                heldout[r["bag"]] = pc.number(r, "heldout_error_m", cv_path)
        groups = {}
        for r in corrected:
            if r["bag"] not in heldout:
                raise pc.InputError(f"{cv_path}: no held-out error (scheme point) for "
                                    f"{r['bag']} of {corrected_path}")
            groups.setdefault((r["light"], r["preset"]), []).append(r)
        total = [0] * 6
        for key in sorted(groups, key=lambda s: pc.scenario_key(*s)) + [None]:
            if key is None:
                n, oi, oh, ci, ch, margin_sum = total
                scen = ("all", "")
            else:
                n = oi = oh = ci = ch = 0
                margin_sum = 0.0
                for r in groups[key]:
                    d = pc.number(r, "distance_m", corrected_path)
                    c = pc.number(r, "corrected_m", corrected_path)
                    ksig = c - pc.number(r, "margin_m", corrected_path)
                    c_held = d - heldout[r["bag"]]  # error = predicted - target
                    n += 1
                    oi += c - d > OVER_READ_M
                    oh += c_held - d > OVER_READ_M
                    ci += d >= c - ksig
                    ch += d >= c_held - ksig
                    margin_sum += ksig
                total = [a + b for a, b in zip(total, [n, oi, oh, ci, ch, margin_sum])]
                scen = key
            rows.append([label, scen[0], scen[1], n, oi, oh, ci, ch, fmt(margin_sum / n)])
            name = "all" if key is None else f"{scen[0]}/{scen[1]}"
            md.append(f"| {label} | {name} | {oi} / {oh} of {n} | {ci} / {ch} of {n} | "
                      f"{margin_sum / n:.2f} |")
    write_atomic(os.path.join(out_dir, "safety_table.csv"), csv_text(header, rows))
    write_atomic(os.path.join(out_dir, "safety_table.md"), "\n".join(md) + "\n")


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--paper6", required=True, help="fit_bias --model paper6 weights YAML")
    ap.add_argument("--article", required=True, help="the article's Table 6 CSV")
    ap.add_argument("--weights", action="append", default=[],
                    help="further weights YAML for the cross-validation table")
    ap.add_argument("--safety", nargs=3, action="append", default=[],
                    metavar=("LABEL", "CORRECTED", "CV"),
                    help="a model's correct_depth output and fit_bias --cv-out")
    ap.add_argument("--k", type=float, default=2.0, help="the k of correct_depth --k (label)")
    ap.add_argument("--out-dir", required=True)
    ap.add_argument("--check-table6", type=float, metavar="TOL",
                    help="exit with status 1 when a weight, RMSE or MAE differs from the "
                         "article's by more than TOL")
    args = ap.parse_args()
    worst = table6(args.paper6, args.article, args.out_dir)
    cv_table([args.paper6] + args.weights, args.article, args.out_dir)
    if args.safety:
        safety_table(args.safety, args.k, args.out_dir)
    if args.check_table6 is not None and not worst <= args.check_table6:
        print(f"plot_tables.py: {args.paper6}: Table 6 differs from {args.article} by "
              f"{worst:.4f} > {args.check_table6}", file=sys.stderr)
        sys.exit(1)


if __name__ == "__main__":
    pc.run_main(sys.argv[0], main)
