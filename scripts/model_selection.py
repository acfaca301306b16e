#!/usr/bin/env python3
"""Cross-validation table of every bias model form on a metrics CSV, beside the article's
in-sample RMSE, and an honest choice of the default form.

Runs the real fit_bias for every form with its default loss (paper6: plain squares, as the
article; disparity forms: Huber at 1 m, fixed beforehand from the sensor's noise: the D455
depth RMS at 16 m is about Z^2 * 0.08 px / (f B) = 0.34 m, so a residual above 1 m is a failed
recording) and also with plain squares, then:

- prints in-sample, leave-one-test-point-out (LOTPO) and leave-one-distance-out (LODO)
  RMSE / MAE per scenario;
- chooses the form for each scenario WITHOUT that scenario's data: the form with the lowest
  mean LOTPO RMSE over the other scenarios (leave-one-scenario-out selection), and prints that
  choice's LOTPO RMSE, which is then an out-of-sample figure for the whole procedure.

Usage: scripts/model_selection.py [--bin build/apps] [--in config/data/paper_d455_outdoor.csv]
"""
import argparse
import os
import re
import subprocess
import sys
import tempfile

ARTICLE_IN_SAMPLE = {"daylight/HA": 0.635, "daylight/HD": 0.541, "sunset/HA": 0.550,
                     "sunset/HD": 0.461}


def run(bin_dir, path, model, loss):
    with tempfile.TemporaryDirectory() as tmp:
        cmd = [os.path.join(bin_dir, "fit_bias"), "--in", path, "--out",
               os.path.join(tmp, "w.yaml"), "--model", model, "--loss", loss,
               "--cv", "point,distance"]
        out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    seconds = float(re.search(r"([\d.]+) s\n", out).group(1))
    table = {}
    for line in out.splitlines()[2:]:
        f = line.split()
        if len(f) < 8 or not re.match(r"^\d+$", f[1]):
            continue
        table[f[0]] = dict(rmse=float(f[2]), mae=float(f[3]), lotpo=float(f[4]),
                           lotpo_mae=float(f[5]), lodo=float(f[6]), lodo_mae=float(f[7]))
    return table, seconds


def main():
    ap = argparse.ArgumentParser()
    here = os.path.dirname(os.path.abspath(__file__))
    ap.add_argument("--bin", default=os.path.join(here, "..", "build", "apps"))
    ap.add_argument("--in", dest="path",
                    default=os.path.join(here, "..", "config", "data", "paper_d455_outdoor.csv"))
    args = ap.parse_args()
    candidates = [("disp_knots", "auto"), ("disp_tan", "auto"), ("disp_scale", "auto"),
                  ("paper6", "auto"), ("disp_knots", "none"), ("disp_tan", "none"),
                  ("disp_scale", "none"), ("paper6", "huber")]
    results = {}
    for model, loss in candidates:
        results[(model, loss)] = run(args.bin, args.path, model, loss)
    scenarios = list(ARTICLE_IN_SAMPLE)
    print("RMSE / MAE [m] per scenario: in-sample | LOTPO | LODO   (fit + both CVs: seconds)")
    print("%-18s" % "model/loss" + "".join("%-40s" % s for s in scenarios))
    for (model, loss), (t, sec) in results.items():
        cells = ["%.3f/%.3f | %.3f/%.3f | %.3f/%.3f" % (t[s]["rmse"], t[s]["mae"], t[s]["lotpo"],
                                                       t[s]["lotpo_mae"], t[s]["lodo"],
                                                       t[s]["lodo_mae"]) for s in scenarios]
        print("%-18s" % (model + "/" + loss) + "".join("%-40s" % c for c in cells) +
              " %.3f s" % sec)
    print("%-18s" % "article in-sample" + "".join("%-40s" % ("%.3f" % ARTICLE_IN_SAMPLE[s])
                                                  for s in scenarios))
    print("\nLeave-one-scenario-out choice among the forms with their default loss:")
    defaults = [c for c in candidates if c[1] == "auto"]
    p6 = results[("paper6", "auto")][0]
    for s in scenarios:
        others = [o for o in scenarios if o != s]
        score = {c: sum(results[c][0][o]["lotpo"] for o in others) / len(others)
                 for c in defaults}
        best = min(score, key=score.get)
        got = results[best][0][s]["lotpo"]
        print("  %-12s chosen %-18s LOTPO %.3f  (paper6 %.3f, article in-sample %.3f)%s" %
              (s, best[0] + "/" + best[1], got, p6[s]["lotpo"], ARTICLE_IN_SAMPLE[s],
               "  beats paper6" if got < p6[s]["lotpo"] else "  DOES NOT beat paper6"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
