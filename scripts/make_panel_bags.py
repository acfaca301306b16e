#!/usr/bin/env python3
"""Writes RealSense bags of a panel scene with known truth, using librealsense's own recorder.

A level D455 depth camera (1280x720, fx = fy = 640 px, no distortion) stands 1.3 m above a flat
ground. A 1 x 1 m panel, its centre 1.0 m above the ground, stands upright facing the camera at
one of the article's 16 test points (4, 8, 12, 16 m x 0, 10, 20, 35 deg to the right). Each
frame is ray-cast, turned into disparity d = f*B/Z, given Gaussian disparity noise, quantized to
1/32 px and turned back into 1 mm depth counts. Random holes (independent in every frame) take
5 % to 99 % of the panel's pixels, rising with distance and angle as in the article's hardest
conditions (16 m, 35 deg, 99 %); the background loses 0.9 times that share. Bags whose truth
file is newer than this script are kept, not recorded again. Recordings with few
valid panel pixels get more frames so that the panel's normal stays measurable (see FRAMES).

Next to every bag: <name>.truth.json (true median depth over the panel footprint, true hole
rate over that footprint and every frame, direction of the panel centre, normal tilt, the
footprint as row runs). In OUT_DIR also: manifest.csv and boxes.json (a hand-drawn-like box
inside each panel, for --region-mode box).

Usage: make_panel_bags.py OUT_DIR [--only NAME] [--bench FRAMES] [--uncompressed]
  --bench N   instead: one 1280x720 recording of N frames at 8 m, 20 deg (bench_panel.bag)
"""
import argparse
import json
import math
import os
import sys
import time

import numpy as np

import rs_record

W, H, FX, PPX, PPY = 1280, 720, 640.0, 640.0, 360.0
BASELINE_M = 0.095
NOISE_PX = 0.05          # disparity noise sigma (D455 outdoors, DESIGN.md: 0.05-0.1 px)
CAMERA_HEIGHT_M = 1.3
PANEL_CENTER_HEIGHT_M = 1.0
PANEL_SIZE_M = 1.0
MAX_RANGE_M = 60.0
DISTANCES = [4, 8, 12, 16]
ANGLES = [0, 10, 20, 35]
HOLES = {  # share of the panel's pixels without depth, per (distance, angle)
    4: [0.05, 0.10, 0.20, 0.35], 8: [0.15, 0.30, 0.50, 0.70],
    12: [0.25, 0.50, 0.75, 0.90], 16: [0.40, 0.70, 0.90, 0.99]}
MIN_FRAMES, MAX_FRAMES = 20, 300


def frames_for(distance_m, hole_rate):
    """Enough frames for ~ (sigma_Z / (0.29 m * 0.6 deg))^2 valid panel samples, i.e. a normal
    known to about 0.6 deg (one third of the 2 deg tolerance)."""
    sigma_z = distance_m ** 2 * NOISE_PX / (FX * BASELINE_M)
    need = (sigma_z / (0.29 * math.radians(0.6))) ** 2
    px = (FX * PANEL_SIZE_M / distance_m) ** 2
    return int(min(MAX_FRAMES, max(MIN_FRAMES, math.ceil(need / (px * (1 - hole_rate))))))


class Quad:
    def __init__(self, center, axis_w, axis_h, w, h):
        self.c, self.aw, self.ah = (np.asarray(a, float) for a in (center, axis_w, axis_h))
        self.w, self.h = w, h
        self.n = np.cross(self.aw, self.ah)

    def hit(self, rays):
        """Z where each ray (x/z, y/z, 1) meets the rectangle, inf elsewhere."""
        nr = rays @ self.n
        with np.errstate(divide="ignore", invalid="ignore"):
            z = np.where(np.abs(nr) > 1e-12, (self.n @ self.c) / nr, np.inf)
        z = np.where(z > 0, z, np.inf)
        q = np.where(np.isfinite(z), z, 0.0)[:, None] * rays - self.c
        inside = (np.abs(q @ self.aw) <= self.w / 2) & (np.abs(q @ self.ah) <= self.h / 2)
        return np.where(inside & np.isfinite(z), z, np.inf)


def scene(distance_m, angle_deg, clutter=False):
    a = math.radians(angle_deg)
    dy = CAMERA_HEIGHT_M - PANEL_CENTER_HEIGHT_M  # camera y points down
    horiz = math.sqrt(distance_m ** 2 - dy ** 2)
    center = [horiz * math.sin(a), dy, horiz * math.cos(a)]
    panel = Quad(center, [math.cos(a), 0, -math.sin(a)], [0, -1, 0], PANEL_SIZE_M, PANEL_SIZE_M)
    others = []
    if clutter:  # a 3 x 2 m wall farther and to the other side, a 0.4 m box nearer
        b = -a - math.radians(20)
        r = distance_m + 4
        others.append(Quad([r * math.sin(b), CAMERA_HEIGHT_M - 1.0, r * math.cos(b)],
                           [math.cos(b), 0, -math.sin(b)], [0, -1, 0], 3.0, 2.0))
        c = a + math.radians(-12 if a >= 0 else 12)
        rb = 0.6 * distance_m
        bc = np.array([rb * math.sin(c), CAMERA_HEIGHT_M - 0.2, rb * math.cos(c)])
        ex, ez = np.array([math.cos(c), 0, -math.sin(c)]), np.array([math.sin(c), 0, math.cos(c)])
        up = np.array([0, -1, 0])
        others += [Quad(bc - 0.2 * ez, ex, up, 0.4, 0.4), Quad(bc - 0.2 * ex, ez, up, 0.4, 0.4),
                   Quad(bc + 0.2 * ex, ez, up, 0.4, 0.4), Quad(bc - 0.2 * up, ex, ez, 0.4, 0.4)]
    u, v = np.meshgrid(np.arange(W), np.arange(H))
    rays = np.stack([(u.ravel() - PPX) / FX, (v.ravel() - PPY) / FX, np.ones(W * H)], axis=1)
    with np.errstate(divide="ignore"):
        z = np.where(rays[:, 1] > 1e-9, CAMERA_HEIGHT_M / rays[:, 1], np.inf)
    for q in others:
        z = np.minimum(z, q.hit(rays))
    zp = panel.hit(rays)
    footprint = np.isfinite(zp) & (zp <= z)
    z = np.where(footprint, zp, z)
    z = np.where(z * np.linalg.norm(rays, axis=1) < MAX_RANGE_M, z, 0.0)
    return panel, z, footprint


def render(z, footprint, hole_rate, rng):
    fb = FX * BASELINE_M
    valid = z > 0
    d = np.zeros_like(z)
    d[valid] = fb / z[valid] + rng.normal(0.0, NOISE_PX, int(valid.sum()))
    d = np.round(d * 32.0) / 32.0  # 1/32 px subpixel step
    holes = rng.random(z.size) < np.where(footprint, hole_rate, 0.9 * hole_rate)
    ok = valid & (d > 0) & ~holes
    counts = np.zeros(z.size, np.uint16)
    zz = fb / d[ok]
    counts[ok] = np.where(zz < 65.0, np.rint(zz * 1000.0), 0).astype(np.uint16)
    return counts.reshape(H, W)


def runs(mask):
    """Footprint as [v, u_begin, u_end) runs."""
    out = []
    for v in np.nonzero(mask.any(axis=1))[0]:
        row = np.concatenate([[0], mask[v].astype(np.int8), [0]])
        edges = np.nonzero(np.diff(row))[0]
        out += [[int(v), int(s), int(e)] for s, e in zip(edges[::2], edges[1::2])]
    return out


def inner_box(mask, margin=1):
    """A box inside the footprint as a careful hand draws it: centred on the middle of the
    panel's image (its pixel centroid), as wide as the nearer side edge allows, as tall as every
    one of its columns is covered, less a margin: [u0, v0, u1, v1) in pixels."""
    vs, us = np.nonzero(mask)
    uc, row = us.mean() + 0.5, int(round(vs.mean()))
    cols = np.nonzero(mask[row])[0]
    half = min(uc - cols[0], cols[-1] + 1 - uc) - margin
    u0, u1 = int(math.ceil(uc - half)), int(math.floor(uc + half))
    sub = mask[:, u0:u1]
    top = max(np.argmax(sub[:, k]) for k in range(sub.shape[1]))
    bottom = min(H - np.argmax(sub[::-1, k]) for k in range(sub.shape[1]))
    return [u0, int(top + margin), u1, int(bottom - margin)]


def make(out, name, distance_m, angle_deg, hole_rate, frames, clutter, compress, seed):
    panel, z, footprint = scene(distance_m, angle_deg, clutter)
    rng = np.random.default_rng(seed)
    stats = {"holes": 0, "pixels": 0}

    def frame(i):
        img = render(z, footprint, hole_rate, rng)
        stats["holes"] += int((img.ravel()[footprint] == 0).sum())
        stats["pixels"] += int(footprint.sum())
        return img

    preset, emitter = (3, 1) if seed % 2 else (4, 0)
    path = os.path.join(out, name + ".bag")
    if os.path.exists(path):
        os.remove(path)
    camera = rs_record.Camera(W, H, FX, FX, PPX, PPY, 0.001, BASELINE_M)
    rs_record.record(path, frame, frames, camera, preset, emitter, compress)
    c = panel.c
    mask = footprint.reshape(H, W)
    truth = dict(
        bag=name + ".bag", distance_m=distance_m, angle_deg=angle_deg, frames=frames,
        clutter=clutter, noise_px=NOISE_PX, baseline_m=BASELINE_M, fx=FX,
        preset="HA" if preset == 3 else "HD", emitter="on" if emitter else "off",
        true_median_depth_m=float(np.median(z[footprint])),
        true_hole_rate_pct=100.0 * stats["holes"] / stats["pixels"], nominal_hole_rate=hole_rate,
        azimuth_deg=math.degrees(math.atan2(c[0], c[2])),
        elevation_deg=math.degrees(math.atan2(-c[1], math.hypot(c[0], c[2]))),
        normal_tilt_deg=math.degrees(math.acos(abs(panel.n[2]))),
        panel_center_m=list(map(float, c)), footprint_px=int(footprint.sum()),
        footprint_runs=runs(mask), box=inner_box(mask))
    with open(os.path.join(out, name + ".truth.json"), "w") as f:
        json.dump(truth, f, separators=(",", ":"))
    return truth


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("out")
    ap.add_argument("--only")
    ap.add_argument("--bench", type=int, default=0)
    ap.add_argument("--uncompressed", action="store_true")
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    if args.bench:
        make(args.out, "bench_panel", 8, 20, 0.30, args.bench, False, False, 99)
        return
    jobs = []
    seed = 1
    for d in DISTANCES:
        for k, a in enumerate(ANGLES):
            jobs.append(("panel_%02dm_%02ddeg" % (d, a), d, a, HOLES[d][k], False, seed))
            seed += 1
    jobs.append(("clutter_08m_20deg", 8, 20, 0.30, True, seed))
    jobs.append(("clutter_12m_00deg", 12, 0, 0.50, True, seed + 1))
    manifest, boxes = ["bag,distance_m,angle_deg,light"], {}
    script_time = max(os.path.getmtime(os.path.abspath(__file__)),
                      os.path.getmtime(os.path.abspath(rs_record.__file__)))
    for name, d, a, hole, clutter, s in jobs:
        if args.only and args.only != name:
            continue
        t0 = time.time()
        truth_file = os.path.join(args.out, name + ".truth.json")
        bag_file = os.path.join(args.out, name + ".bag")
        if (os.path.exists(bag_file) and os.path.exists(truth_file)
                and os.path.getmtime(truth_file) > script_time):
            with open(truth_file) as f:  # written by this version of the script: kept
                truth = json.load(f)
        else:
            truth = make(args.out, name, d, a, hole, frames_for(d, hole), clutter,
                         not args.uncompressed, s)
        manifest.append("%s.bag,%g,%g,%s" % (name, d, a, "daylight" if s % 3 else "sunset"))
        boxes[name + ".bag"] = truth["box"]
        print("%s: %d frames, %.0f%% holes, %.1fs" % (name, truth["frames"],
              truth["true_hole_rate_pct"], time.time() - t0), flush=True)
    with open(os.path.join(args.out, "manifest.csv"), "w") as f:
        f.write("\n".join(manifest) + "\n")
    with open(os.path.join(args.out, "boxes.json"), "w") as f:
        json.dump(boxes, f, indent=1)


if __name__ == "__main__":
    sys.exit(main())
