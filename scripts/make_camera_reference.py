#!/usr/bin/env python3
"""Writes tests/data/camera_reference.csv: pixels deprojected and points projected by librealsense
itself (pyrealsense2 2.56.5's rs2_deproject_pixel_to_point / rs2_project_point_to_pixel), for
every distortion model depthbias supports, with D455-like depth and color intrinsics.

The coefficient sets are typical of a D455 as librealsense reports them: the depth stream
reports Brown-Conrady with all coefficients zero; the color stream reports Inverse Brown-Conrady
with small radial and tangential terms. A third, stronger set exercises the iterative undistortion
(10 iterations in librealsense). The grid reaches the image corners.
"""
import csv
import sys

import pyrealsense2 as rs

MODELS = {
    "none": rs.distortion.none,
    "brown_conrady": rs.distortion.brown_conrady,
    "inverse_brown_conrady": rs.distortion.inverse_brown_conrady,
    "modified_brown_conrady": rs.distortion.modified_brown_conrady,
}
# (name, width, height, fx, fy, ppx, ppy, coeffs)
CAMERAS = [
    ("d455_depth", 1280, 720, 645.61, 645.61, 643.02, 361.47, [0.0, 0.0, 0.0, 0.0, 0.0]),
    ("d455_color", 1280, 720, 642.72, 641.86, 646.33, 362.95,
     [-0.05524, 0.06524, -0.00061, 0.00063, -0.02095]),
    ("strong", 1280, 720, 640.0, 640.0, 640.0, 360.0, [-0.25, 0.08, 0.002, -0.0015, -0.01]),
]
DEPTHS_M = [0.6, 4.0, 16.0]


def grid(width, height, nu=9, nv=7):
    us = [i * (width - 1) / (nu - 1) for i in range(nu)]
    vs = [j * (height - 1) / (nv - 1) for j in range(nv)]
    return [(u, v) for v in vs for u in us] + [(-0.5, -0.5), (width - 0.5, height - 0.5)]


def main(out_path):
    rows = []
    for cam_name, w, h, fx, fy, ppx, ppy, coeffs in CAMERAS:
        for model_name, model in MODELS.items():
            intr = rs.intrinsics()
            intr.width, intr.height = w, h
            intr.fx, intr.fy, intr.ppx, intr.ppy = fx, fy, ppx, ppy
            intr.model = model
            intr.coeffs = coeffs
            base = [cam_name, model_name, w, h, fx, fy, ppx, ppy] + coeffs
            for k, (u, v) in enumerate(grid(w, h)):
                z = DEPTHS_M[k % len(DEPTHS_M)]
                p = rs.rs2_deproject_pixel_to_point(intr, [u, v], z)
                rows.append(base + ["deproject", u, v, z, p[0], p[1], p[2]])
                # A point on the pinhole ray of (u, v), projected back through the model.
                x, y = (u - ppx) / fx, (v - ppy) / fy
                pt = [x * z, y * z, z]
                px = rs.rs2_project_point_to_pixel(intr, pt)
                rows.append(base + ["project", px[0], px[1], z, pt[0], pt[1], pt[2]])
    with open(out_path, "w", newline="") as f:
        wr = csv.writer(f, lineterminator="\n")
        wr.writerow(["camera", "model", "width", "height", "fx", "fy", "ppx", "ppy",
                     "k1", "k2", "p1", "p2", "k3", "op", "u", "v", "depth_m", "x", "y", "z"])
        for r in rows:
            wr.writerow([f"{c:.9g}" if isinstance(c, float) else c for c in r])
    print(f"{out_path}: {len(rows)} rows")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "tests/data/camera_reference.csv")
