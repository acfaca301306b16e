#!/usr/bin/env python3
"""Prints panel_extract's results on the field scenes against their truth, as a Markdown table.

One row per recording, ordered by distance, angle and preset: the median's error [mm] (and its
tolerance, one 1/32 px disparity step + 0.1 % of Z), the hole rate's error [points], the normal
tilt measured and true [deg], the panel height and width measured [m], whether the panel was
found (the measured centre's direction falls on the panel's own footprint, not on the bush,
person, post or grass), and which hazards the scene adds. An asterisk marks a figure outside
the tolerances that tests/panel/field_scenes_test.cpp holds it to (tilt: 2 deg, or 3.5 standard
errors of a plane fitted to the panel's own valid samples where those cannot give 2 deg).

Usage: field_scenes_table.py BAGS_DIR METRICS_CSV [PANELS_JSON]
  BAGS_DIR     the folder make_field_bags.py wrote (its *.truth.json)
  METRICS_CSV  panel_extract --out of a run over those bags (with or without --manifest)
  PANELS_JSON  the same run's --panels-out: "found right" then judges the detection's centre
               (center_m), as the test does, instead of the measured direction in METRICS_CSV
"""
import argparse
import csv
import json
import math
import os
import sys


def number(row, key):
    try:
        return float(row[key])
    except (KeyError, ValueError):
        return float("nan")


def centre_on_panel(row, panel, t):
    """The pixel under the detection's centre (panel: its panels.json entry) or, without one,
    the pixel the measured centre's direction points at, lies in the panel's footprint."""
    if panel is not None:
        c = panel.get("center_m")
        if not c or not c[2] > 0:
            return False
        u, v = t["ppx"] + t["fx"] * c[0] / c[2], t["ppy"] + t["fy"] * c[1] / c[2]
    else:
        az = math.radians(number(row, "azimuth_deg"))
        el = math.radians(number(row, "elevation_deg"))
        if not (math.isfinite(az) and math.isfinite(el)):
            return False
        u = t["ppx"] + t["fx"] * math.tan(az)
        v = t["ppy"] - t["fy"] * math.tan(el) / math.cos(az)
    u, v = math.floor(u), math.floor(v)
    return any(r[0] == v and r[1] <= u < r[2] for r in t["footprint_runs"])


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("bags")
    ap.add_argument("metrics")
    ap.add_argument("panels", nargs="?")
    args = ap.parse_args()
    panels = None
    if args.panels:
        with open(args.panels) as f:
            panels = {p["bag"]: p for p in json.load(f)}
    with open(args.metrics, newline="") as f:
        rows = list(csv.DictReader(f))
    table = []
    for row in rows:
        truth_file = os.path.join(args.bags, os.path.splitext(row["bag"])[0] + ".truth.json")
        if not os.path.exists(truth_file):
            sys.exit("%s: no truth for %s (%s)" % (args.metrics, row["bag"], truth_file))
        with open(truth_file) as f:
            t = json.load(f)
        table.append((t["distance_m"], t["angle_deg"], t["preset"], row["bag"], row, t))
    table.sort(key=lambda x: x[:4])

    cols = ["scene", "dist [m]", "angle [deg]", "preset", "median err [mm]", "tol [mm]",
            "hole err [pt]", "azimuth err [deg]", "tilt [deg] (true)", "height [m]", "width [m]",
            "found right", "status", "hazards"]
    print("| " + " | ".join(cols) + " |")
    print("|" + "---|" * len(cols))
    counts = {"ok": 0, "found": 0, "within": 0}
    fmt = lambda v, spec: (spec % v) if math.isfinite(v) else "-"
    for d, a, preset, bag, row, t in table:
        z = t["true_median_depth_m"]
        tol_m = z * z / (32 * t["fx"] * t["baseline_m"]) + 0.001 * z
        tol_tilt = max(2.0, 3.5 * t["tilt_sigma_deg"])
        ok = row["status"] == "ok"
        e_med = number(row, "median_m") - z
        e_hole = number(row, "hole_rate_pct") - t["true_hole_rate_pct"]
        e_az = number(row, "azimuth_deg") - t["azimuth_deg"]
        tilt = number(row, "normal_tilt_deg")
        height, width = number(row, "panel_height_m"), number(row, "panel_width_m")
        found = ok and centre_on_panel(row, None if panels is None else
                                       panels.get(row["bag"], {}), t)
        checks = [abs(e_med) <= tol_m, abs(e_hole) <= 1.0, abs(e_az) <= 0.5,
                  abs(tilt - t["normal_tilt_deg"]) <= tol_tilt, abs(height - 1.0) <= 0.1,
                  abs(width - 1.0) <= 0.1]
        star = ["" if c else "*" for c in checks]
        counts["ok"] += ok
        counts["found"] += found
        counts["within"] += found and all(checks)
        hazards = ", ".join(t["scene"]["hazards"] + (["bush"] if t["bush"] else []))
        cells = [os.path.splitext(bag)[0], "%g" % d, "%g" % a, preset,
                 fmt(1000 * e_med, "%+.0f") + star[0], "%.0f" % (1000 * tol_m),
                 fmt(e_hole, "%+.1f") + star[1], fmt(e_az, "%+.2f") + star[2],
                 "%s%s (%.1f)" % (fmt(tilt, "%.1f"), star[3], t["normal_tilt_deg"]),
                 fmt(height, "%.2f") + star[4], fmt(width, "%.2f") + star[5],
                 "yes" if found else "no", row["status"], hazards]
        print("| " + " | ".join(cells) + " |")
    n = len(table)
    print("\n%d recordings: %d with a panel (status ok), %d found right, %d found and measured "
          "within every tolerance (median, hole rate, azimuth, tilt, height, width)."
          % (n, counts["ok"], counts["found"], counts["within"]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
