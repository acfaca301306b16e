#!/usr/bin/env python3
"""Writes a user's own campaign as RealSense bags of field scenes (make_field_bags.py's scenes,
not the simulator's renderer): one light (daylight), one preset (High Accuracy), the article's
16 test points (4, 8, 12, 16 m x 0, 10, 20, 35 deg) x emitter off and on: 32 bags, and a
manifest with the nominal distances.

What the unit and the field add, and the proof (scripts/gap_cases.sh) knows:
- every disparity read DELTA px too large (--disparity-offset-px, -0.25 by default: a unit that
  reads 1.1 m far at 16 m);
- each test point placed off by its own range error (2 % of the distance, --placement-pct),
  the same for its two recordings (one placement of the panel);
- make_field_bags.py's field: the camera 1.1 m above uneven grass, a hedge at 40 m, a bush in
  view, the panel on a post. The camera is level and the panel faces it, as the protocol says
  (config/protocol_paper.yaml): a turned panel is a registered effect (panel_tilt), and the
  proof's answer must be the offset alone.
The camera's noise and holes are the base sensor's for daylight/HA (config/sensor_calibrated.yaml:
sigma_d 0.0698 px, holes 71 % of the panel's pixels), so that what differs from the simulator is
the field and the offset.

Usage: make_field_campaign.py OUT_DIR [--disparity-offset-px D] [--placement-pct P]
                              [--seed S] [--frames N] [--jobs N]
"""
import argparse
import math
import multiprocessing
import os
import sys
import time
import zlib

import numpy as np

import make_field_bags as fb

DISTANCES_M = (4, 8, 12, 16)
ANGLES_DEG = (0, 10, 20, 35)
SIGMA_PX = 0.0698  # config/sensor_calibrated.yaml, daylight/HA
PANEL_HOLES = 0.71


def campaign(offset_px, placement_pct, seed, frames):
    """The 32 scenes and their nominal (distance, angle)."""
    out = []
    for d in DISTANCES_M:
        for a in ANGLES_DEG:
            rng = np.random.default_rng(zlib.crc32(b"%d %d %d" % (seed, d, a)))
            placed = d * (1 + placement_pct / 100 * rng.standard_normal())
            # The bush (6 m) on the other side of the axis, never in front of the panel.
            bush = float((-1 if a > 0 else rng.choice([-1, 1])) * rng.uniform(8, 20))
            for emitter in (0, 1):
                name = "unit_daylight_emitter-%s_%02dm_%02ddeg_HA" % (
                    "on" if emitter else "off", d, a)
                sc = fb.Scene(name, placed, a, "HA", yaw_deg=0.0, pitch_deg=0.0, bush_deg=bush,
                              emitter=emitter,
                              sigma_px=SIGMA_PX, panel_holes=PANEL_HOLES, frames=frames,
                              disparity_offset_px=offset_px)
                out.append((sc, d, a))
    return out


def make(job):
    out, sc = job
    return fb.make(out, sc, sc.frames)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("out")
    ap.add_argument("--disparity-offset-px", type=float, default=-0.25)
    ap.add_argument("--placement-pct", type=float, default=2.0)
    ap.add_argument("--seed", type=int, default=7000)
    ap.add_argument("--frames", type=int, default=10)
    ap.add_argument("--jobs", type=int, default=1)
    args = ap.parse_args()
    if not (-2 <= args.disparity_offset_px <= 2) or not (0 <= args.placement_pct <= 20):
        ap.error("--disparity-offset-px in [-2, 2] and --placement-pct in [0, 20]")
    os.makedirs(args.out, exist_ok=True)
    scenes = campaign(args.disparity_offset_px, args.placement_pct, args.seed, args.frames)
    t0 = time.time()
    jobs = [(args.out, sc) for sc, _, _ in scenes]
    if args.jobs > 1:
        with multiprocessing.get_context("spawn").Pool(args.jobs) as pool:
            truths = pool.map(make, jobs, chunksize=1)
    else:
        truths = [make(j) for j in jobs]
    rows = ["bag,distance_m,angle_deg,light,preset,emitter"]
    for (sc, d, a), truth in zip(scenes, truths):
        rows.append("%s.bag,%g,%g,daylight,HA,%s" % (sc.name, d, a, "on" if sc.emitter else "off"))
        print("%-40s placed at %6.3f m, median %7.3f m" % (sc.name, sc.distance_m,
                                                            truth["true_median_depth_m"]))
    fb.write(os.path.join(args.out, "manifest.csv"), "\n".join(rows) + "\n")
    print("%d recordings in %.1f s" % (len(scenes), time.time() - t0))
    return 0


if __name__ == "__main__":
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    sys.exit(main())
