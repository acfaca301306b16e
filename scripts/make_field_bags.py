#!/usr/bin/env python3
"""Writes RealSense bags of field scenes with known truth, using librealsense's own recorder.

What a field looks like to a D455 on a machine: the camera 1.1 m above uneven grass, pitched
2 deg down (some scenes level, two rolled 3 deg); the article's 1 x 1 m grey panel on a 6 cm
post, its bottom edge 0.55 m above the grass, the post in the panel's plane down into the grass,
the panel turned 0-3 deg (yaw) off the image plane; a hedge closing the scene at 40 m; a bush
(0.8 x 1.2 m block of rough, well-textured vegetation) 6 m away to one side; in some scenes a
person (0.5 x 0.3 x 1.75 m box with a rough surface) beside the panel at its distance. Nothing
stands in front of the panel (checked).

Every frame is ray-cast (numpy, vectorized), turned into disparity d = fx*B/Z (B = 0.095 m),
given Gaussian disparity noise sigma_d (0.08 px, 0.15 px in the noisy group), quantized to 1/32
px and turned back into depth counts (1 mm, one scene 100 um). Holes are drawn independently in
every frame: under High Accuracy 97-99 % of the textureless panel's pixels and ~20 % of the
grass, hedge and vegetation; under High Density 30-60 % of the panel; pixels straddling the
panel's outline are more often invalid. The grass is a smooth height field (~3 cm RMS,
wavelengths 5-15 m) plus a static per-pixel depth roughness of 0.4 % of the range; bush, person
and hedge carry their own static roughness.

Next to every bag: <name>.truth.json: the panel's own footprint (pixels whose centre ray meets
the panel rectangle, not the post) as [v, u_begin, u_end) runs, the true median depth of the
panel's valid samples over every frame on that footprint shrunk by 1 px (what the generated
counts say there), the hole rate of the same pixels (and of the whole footprint), direction,
range and normal tilt of the panel, its size, the expected standard error of a normal fitted to
those samples, the footprints of the post, bush and person (for diagnostics), and every
parameter of the scene. In OUT_DIR also manifest.csv (bag,distance_m,angle_deg,light,preset,
emitter) and boxes.json (a box inside each panel for --region-mode box, as make_panel_bags.py
draws them). Bags whose truth file is newer than this script (and rs_record.py) are kept.

Usage: make_field_bags.py OUT_DIR [--only NAME] [--frames N] [--jobs N] [--list]
  --list      print the scene names, one per line, and exit (OUT_DIR not needed)
  --frames N  N frames in every bag instead of each scene's own count
  --jobs N    record N scenes at a time (separate processes)
"""
import argparse
import json
import math
import multiprocessing
import os
import sys
import time
import zlib
from dataclasses import asdict, dataclass, field

import numpy as np

import rs_record
from make_panel_bags import inner_box

HERE = os.path.dirname(os.path.abspath(__file__))

W, H = 1280, 720
BASELINE_M = 0.095
CAMERA_HEIGHT_M = 1.1
PANEL_SIZE_M = 1.0
PANEL_BOTTOM_M = 0.55       # panel's bottom edge above the grass
POST_WIDTH_M = 0.06
POST_BURIED_M = 0.3         # the post goes on below the grass surface (hidden by it)
GRASS_HEIGHT_RMS_M = 0.03   # smooth height field
GRASS_ROUGHNESS = 0.004     # static per-pixel depth roughness, share of the depth
HEDGE_DISTANCE_M = 40.0     # horizontal distance of the hedge (a vertical surface)
HEDGE_HEIGHT_M = 2.5
HEDGE_ROUGH_M = 0.2
BUSH = dict(width_m=0.8, height_m=1.2, depth_m=0.6, range_m=6.0, bulge_m=0.12, rough_m=0.04)
PERSON = dict(width_m=0.5, depth_m=0.3, height_m=1.75, bulge_m=0.06, rough_m=0.015)
# Hole probability per surface and preset (HD's panel rate rises with distance, see panel_holes).
HOLES = {"HA": dict(grass=0.20, hedge=0.25, bush=0.08, person=0.15, post=0.5, edge=0.6),
         "HD": dict(grass=0.10, hedge=0.15, bush=0.04, person=0.08, post=0.3, edge=0.4)}
HD_PANEL_HOLES = {4: 0.30, 8: 0.40, 12: 0.50, 16: 0.60}
REAL_INTRINSICS = (646.3, 645.1, 636.8, 362.4)  # fx, fy, ppx, ppy of a D455 at 1280x720
LABELS = {"sky": 0, "grass": 1, "hedge": 2, "panel": 3, "post": 4, "bush": 5, "person": 6}


@dataclass
class Scene:
    name: str
    distance_m: float          # range from the camera to the panel centre (nominal)
    angle_deg: float           # horizontal azimuth of the panel centre, to the right
    preset: str                # HA or HD
    yaw_deg: float             # panel turned off the image plane, about the vertical
    pitch_deg: float = 2.0     # camera pitched down
    roll_deg: float = 0.0
    bush_deg: float = None     # azimuth of the bush (None: no bush)
    person: int = 0            # person beside the panel: -1 left, +1 right, 0 none
    person_gap_m: float = 0.2  # between the panel's edge and the person (0.05: holding it)
    panel_holes: float = None  # None: 0.97 (HA, 0.98 from 12 m) or HD_PANEL_HOLES
    sigma_px: float = 0.08     # disparity noise
    disparity_offset_px: float = 0.0  # every disparity read this much too large (a unit's error)
    frames: int = 10
    depth_units_m: float = 0.001
    intrinsics: tuple = (640.0, 640.0, 640.0, 360.0)  # fx, fy, ppx, ppy
    compress: bool = True
    emitter: int = 1
    light: str = "daylight"
    hazards: list = field(default_factory=list)  # what this scene adds to the common ones


def scenes():
    s = []
    ha = lambda d, a, **k: s.append(Scene("field_%02dm_%02ddeg_ha" % (d, a), d, a, "HA", **k))
    hd = lambda d, a, **k: s.append(Scene("field_%02dm_%02ddeg_hd" % (d, a), d, a, "HD", **k))
    # High Accuracy at every test point.
    ha(4, 0, yaw_deg=1.0, bush_deg=14, person=-1, hazards=["person"])
    ha(4, 10, yaw_deg=3.0, bush_deg=-12, pitch_deg=0.0, hazards=["level"])
    ha(4, 20, yaw_deg=2.0, bush_deg=-10, roll_deg=3.0, light="sunset", hazards=["roll"])
    ha(4, 35, yaw_deg=0.5, bush_deg=8, intrinsics=REAL_INTRINSICS, hazards=["intrinsics"])
    ha(8, 0, yaw_deg=2.5, bush_deg=-12)
    ha(8, 10, yaw_deg=1.5, bush_deg=-14, person=1, light="sunset", hazards=["person"])
    ha(8, 20, yaw_deg=3.0, pitch_deg=0.0, hazards=["level", "no bush"])
    ha(8, 35, yaw_deg=0.0, bush_deg=12, emitter=0)
    ha(12, 0, yaw_deg=1.0, bush_deg=-10)
    ha(12, 10, yaw_deg=2.0, bush_deg=22, light="sunset")
    ha(12, 20, yaw_deg=3.0, bush_deg=-12, compress=False, hazards=["uncompressed"])
    ha(12, 35, yaw_deg=1.5, bush_deg=10, pitch_deg=0.0, hazards=["level"])
    ha(16, 0, yaw_deg=2.0, bush_deg=12, person=-1, person_gap_m=0.05,
       hazards=["person holding"])
    ha(16, 10, yaw_deg=3.0, bush_deg=-12, pitch_deg=0.0, light="sunset", hazards=["level"])
    ha(16, 20, yaw_deg=1.0, bush_deg=6, roll_deg=3.0, hazards=["roll"])
    ha(16, 35, yaw_deg=2.5, bush_deg=14, intrinsics=REAL_INTRINSICS, hazards=["intrinsics"])
    # High Density at 4 m and 16 m, and two points between.
    hd(4, 0, yaw_deg=2.0, bush_deg=-12, emitter=0)
    hd(4, 10, yaw_deg=0.5, bush_deg=-14, person=1, person_gap_m=0.05,
       hazards=["person holding"])
    hd(4, 20, yaw_deg=3.0, bush_deg=-10, depth_units_m=0.0001, light="sunset",
       hazards=["100 um units"])
    hd(4, 35, yaw_deg=1.5, bush_deg=8, pitch_deg=0.0, compress=False,
       hazards=["level", "uncompressed"])
    hd(8, 10, yaw_deg=2.0, bush_deg=-12)
    hd(12, 20, yaw_deg=3.0, bush_deg=6, emitter=0, light="sunset")
    hd(16, 0, yaw_deg=1.0, bush_deg=-12)
    hd(16, 10, yaw_deg=3.0, bush_deg=-14, person=1, pitch_deg=0.0, hazards=["person", "level"])
    hd(16, 20, yaw_deg=0.5, bush_deg=-12, light="sunset")
    hd(16, 35, yaw_deg=2.0, bush_deg=20, emitter=0)
    # 1 % valid pixels per frame on the panel.
    for d, a, yaw, bush in ((4, 0, 2.0, -12), (16, 10, 1.0, 20)):
        s.append(Scene("sparse_%02dm_%02ddeg_ha" % (d, a), d, a, "HA", yaw_deg=yaw,
                       bush_deg=bush, panel_holes=0.99, hazards=["1 % valid"]))
    # The calibrated sensor's noise (0.6 m per pixel at 16 m) and few frames.
    for d, a, yaw, bush, n, person in ((4, 10, 2.5, -12, 5, 0), (16, 0, 1.5, -12, 6, 0),
                                       (16, 20, 3.0, -10, 5, 0), (16, 35, 0.5, -12, 6, 1)):
        s.append(Scene("noisy_%02dm_%02ddeg_hd" % (d, a), d, a, "HD", yaw_deg=yaw, bush_deg=bush,
                       person=person, sigma_px=0.15, frames=n,
                       hazards=["sigma 0.15 px", "%d frames" % n] + (["person"] if person else [])))
    return s


def panel_holes(sc):
    if sc.panel_holes is not None:
        return sc.panel_holes
    return HD_PANEL_HOLES[sc.distance_m] if sc.preset == "HD" else (
        0.97 if sc.distance_m < 12 else 0.98)


# ---------------------------------------------------------------------------------------------
# Geometry. World frame: x right, y down (gravity), z forward and horizontal; the camera's centre
# at the origin, the nominal ground plane at y = CAMERA_HEIGHT_M. Depth Z is the camera-frame z
# of a hit, and since every camera ray is (x/z, y/z, 1), a ray's parameter t is that depth.

def rotation(pitch_deg, roll_deg):
    """Camera-to-world rotation: columns are the camera's x, y, z axes in the world."""
    p, r = math.radians(pitch_deg), math.radians(roll_deg)
    x0, y0 = np.array([1.0, 0, 0]), np.array([0, math.cos(p), -math.sin(p)])
    zc = np.array([0, math.sin(p), math.cos(p)])
    xc, yc = math.cos(r) * x0 + math.sin(r) * y0, -math.sin(r) * x0 + math.cos(r) * y0
    return np.stack([xc, yc, zc], axis=1)


class Grass:
    """Smooth height field above the nominal ground [m, up], a sum of plane waves."""

    def __init__(self, rng):
        k = 6
        lam, th = rng.uniform(5.0, 15.0, k), rng.uniform(0, 2 * math.pi, k)
        self.kx, self.kz = 2 * math.pi / lam * np.cos(th), 2 * math.pi / lam * np.sin(th)
        self.ph = rng.uniform(0, 2 * math.pi, k)
        self.amp = GRASS_HEIGHT_RMS_M * math.sqrt(2.0 / k)

    def height(self, x, z):
        return self.amp * np.cos(np.multiply.outer(x, self.kx) + np.multiply.outer(z, self.kz)
                                 + self.ph).sum(axis=-1)

    def hit(self, rays):
        """Depth where each world ray meets the grass (inf if it does not go down)."""
        ry = rays[..., 1]
        down = ry > 1e-6
        r = rays[down]
        t = CAMERA_HEIGHT_M / r[:, 1]
        for _ in range(6):  # damped fixed point of t = (h_cam - height(t*r)) / r_y
            t_new = (CAMERA_HEIGHT_M - self.height(t * r[:, 0], t * r[:, 2])) / r[:, 1]
            t = np.clip(0.5 * (t + t_new), 0.2, 1e4)
        out = np.full(ry.shape, np.inf)
        out[down] = t
        return out


class Quad:
    """A rectangle: centre c, unit axes aw (width) and ah (height), size w x h [m]."""

    def __init__(self, c, aw, ah, w, h):
        self.c, self.aw, self.ah = (np.asarray(a, float) for a in (c, aw, ah))
        self.w, self.h = w, h
        self.n = np.cross(self.aw, self.ah)

    def window(self, cam, R, pad=3):
        """Image rows and columns that can see the quad (the whole image if it is behind)."""
        fx, fy, ppx, ppy = cam
        corners = [self.c + sw * self.w / 2 * self.aw + sh * self.h / 2 * self.ah
                   for sw in (-1, 1) for sh in (-1, 1)]
        pc = np.array(corners) @ R  # world to camera: R^T p
        if (pc[:, 2] < 0.05).any():
            return slice(0, H), slice(0, W)
        u, v = ppx + fx * pc[:, 0] / pc[:, 2], ppy + fy * pc[:, 1] / pc[:, 2]
        cols = np.clip([math.floor(u.min()) - pad, math.ceil(u.max()) + pad], 0, W)
        rows = np.clip([math.floor(v.min()) - pad, math.ceil(v.max()) + pad], 0, H)
        return slice(int(rows[0]), int(rows[1])), slice(int(cols[0]), int(cols[1]))

    def plane(self, rays):
        """Depth t of each ray's hit on the quad's plane and the hit's coordinates (s, q) along
        aw and ah from the centre."""
        nr = rays @ self.n
        with np.errstate(divide="ignore", invalid="ignore"):
            t = np.where(np.abs(nr) > 1e-12, (self.n @ self.c) / nr, np.inf)
        t = np.where(t > 0, t, np.inf)
        p = np.where(np.isfinite(t), t, 0.0)[..., None] * rays - self.c
        return t, p @ self.aw, p @ self.ah

    def hit(self, rays):
        t, s, q = self.plane(rays)
        inside = (np.abs(s) <= self.w / 2) & (np.abs(q) <= self.h / 2)
        return np.where(inside, t, np.inf), s, q


class Canvas:
    """Z-buffer of the scene: depth, surface label."""

    def __init__(self, rays):
        self.rays = rays
        self.z = np.full((H, W), np.inf)
        self.label = np.zeros((H, W), np.int8)

    def put(self, win, z, label):
        zb, lb = self.z[win], self.label[win]
        nearer = z < zb
        zb[nearer] = z[nearer]
        lb[nearer] = label


def block(canvas, cam, R, rng, base_w, width, depth, height, facing, bulge_m, rough_m, label):
    """A rough box standing at base_w (world, on the ground) whose front faces direction
    `facing` (horizontal unit vector from the box towards the camera side): front face bulged
    towards the camera by up to bulge_m, every face with static roughness rough_m."""
    up = np.array([0.0, -1.0, 0.0])
    ad = -facing  # away from the camera
    aw = np.cross(up, ad)
    aw /= np.linalg.norm(aw)
    mid = base_w + up * height / 2
    faces = [Quad(mid - ad * depth / 2, aw, up, width, height),
             Quad(mid - aw * width / 2, ad, up, depth, height),
             Quad(mid + aw * width / 2, ad, up, depth, height),
             Quad(mid + up * height / 2, aw, ad, width, depth)]
    for k, f in enumerate(faces):
        win = f.window(cam, R)
        z, s, q = f.hit(canvas.rays[win])
        if k == 0:  # d = bulge·(1 − (2s/w)²)·sqrt(1 − (2q/h)²), towards the camera
            shape = np.clip(1 - (2 * s / width) ** 2, 0, 1) * np.sqrt(
                np.clip(1 - (2 * q / height) ** 2, 0, 1))
            z = z - bulge_m * shape
        z = z + rough_m * rng.standard_normal(z.shape)
        canvas.put(win, z, label)


@dataclass
class Built:
    z: object          # static depth [m] per pixel, 0 where nothing is seen
    label: object      # surface per pixel (LABELS)
    hole_p: object     # hole probability per pixel
    footprint: object  # panel's own pixels
    inner: object      # footprint pixels at least 1 px inside the outline
    panel: Quad        # world frame
    R: object


def build(sc, rng):
    fx, fy, ppx, ppy = cam = sc.intrinsics
    R = rotation(sc.pitch_deg, sc.roll_deg)
    u, v = np.meshgrid(np.arange(W, dtype=float), np.arange(H, dtype=float))
    rays_c = np.stack([(u - ppx) / fx, (v - ppy) / fy, np.ones_like(u)], axis=-1)
    rays = rays_c @ R.T
    canvas = Canvas(rays)
    grass = Grass(rng)

    # Grass, with its static roughness.
    zg = grass.hit(rays)
    zg *= 1 + GRASS_ROUGHNESS * rng.standard_normal(zg.shape)
    canvas.put(np.s_[:, :], zg, LABELS["grass"])
    # Hedge: vertical surface at HEDGE_DISTANCE_M, ragged top, rough.
    with np.errstate(divide="ignore"):
        th = np.where(rays[..., 2] > 1e-6, HEDGE_DISTANCE_M / rays[..., 2], np.inf)
    xh = th * rays[..., 0]
    top = CAMERA_HEIGHT_M - HEDGE_HEIGHT_M - 0.15 * np.sin(xh / 1.7) - 0.1 * np.sin(xh / 0.6 + 1)
    th = np.where(th * rays[..., 1] >= top, th, np.inf)
    th = th + HEDGE_ROUGH_M * rng.standard_normal(th.shape)
    canvas.put(np.s_[:, :], th, LABELS["hedge"])

    up = np.array([0.0, -1.0, 0.0])

    def on_grass(x, z):
        return np.array([x, CAMERA_HEIGHT_M - float(grass.height(np.array(x), np.array(z))), z])

    # Panel: centre at range distance_m, horizontal azimuth angle_deg, bottom edge PANEL_BOTTOM_M
    # above the grass below it; upright, its normal yawed by yaw_deg from the image plane's.
    a = math.radians(sc.angle_deg)
    dx, dz = math.sin(a), math.cos(a)
    horiz = sc.distance_m
    for _ in range(5):  # the centre's height depends on the grass under it
        base = on_grass(horiz * dx, horiz * dz)
        cy = base[1] - PANEL_BOTTOM_M - PANEL_SIZE_M / 2
        horiz = math.sqrt(sc.distance_m ** 2 - cy ** 2)
    center = np.array([horiz * dx, cy, horiz * dz])
    yaw = math.radians(sc.yaw_deg)
    aw = np.array([math.cos(yaw), 0.0, -math.sin(yaw)])
    panel = Quad(center, aw, up, PANEL_SIZE_M, PANEL_SIZE_M)
    post_len = PANEL_BOTTOM_M + POST_BURIED_M
    post = Quad(center - up * (PANEL_SIZE_M / 2 + post_len / 2), aw, up, POST_WIDTH_M, post_len)

    if sc.bush_deg is not None:
        b = math.radians(sc.bush_deg)
        facing = -np.array([math.sin(b), 0.0, math.cos(b)])
        base = on_grass(BUSH["range_m"] * math.sin(b), BUSH["range_m"] * math.cos(b))
        block(canvas, cam, R, rng, base - facing * BUSH["depth_m"] / 2, BUSH["width_m"],
              BUSH["depth_m"], BUSH["height_m"], facing, BUSH["bulge_m"], BUSH["rough_m"],
              LABELS["bush"])
    if sc.person:
        off = sc.person * (PANEL_SIZE_M / 2 + sc.person_gap_m + PERSON["width_m"] / 2)
        p = center + off * aw
        base = on_grass(p[0], p[2])
        normal = np.cross(aw, up)  # the panel's normal, towards the camera
        block(canvas, cam, R, rng, base, PERSON["width_m"], PERSON["depth_m"],
              PERSON["height_m"], normal, PERSON["bulge_m"], PERSON["rough_m"], LABELS["person"])

    win = post.window(cam, R)
    canvas.put(win, post.hit(rays[win])[0], LABELS["post"])
    win = panel.window(cam, R)
    zp, s, q = panel.plane(rays[win])
    inside = (np.abs(s) <= PANEL_SIZE_M / 2) & (np.abs(q) <= PANEL_SIZE_M / 2)
    canvas.put(win, np.where(inside, zp, np.inf), LABELS["panel"])
    hidden = int((inside & (canvas.label[win] != LABELS["panel"])).sum())
    if hidden:  # the truth is the whole panel's: nothing may stand in front of it
        raise RuntimeError("%s: %d pixels of the panel are hidden" % (sc.name, hidden))
    # Distance of each pixel centre to the panel's outline, in pixels (positive inside).
    with np.errstate(invalid="ignore"):
        edge_px = np.minimum((PANEL_SIZE_M / 2 - np.abs(s)) * fx / zp,
                             (PANEL_SIZE_M / 2 - np.abs(q)) * fy / zp)
    edge_px = np.where(np.isfinite(zp), edge_px, np.inf)

    z = np.where(np.isfinite(canvas.z) & (canvas.z > 0), canvas.z, 0.0)
    label = np.where(z > 0, canvas.label, LABELS["sky"]).astype(np.int8)
    footprint = label == LABELS["panel"]
    inner = np.zeros_like(footprint)
    inner[win] = footprint[win] & (edge_px >= 1.0)
    rates = dict(HOLES[sc.preset], panel=panel_holes(sc), sky=1.0)
    hole_p = np.zeros((H, W))
    for name, k in LABELS.items():
        hole_p[label == k] = rates[name]
    straddle = np.zeros_like(footprint)
    straddle[win] = np.abs(edge_px) < 0.5
    hole_p[straddle] = 1 - (1 - hole_p[straddle]) * (1 - rates["edge"])
    return Built(z, label, hole_p, footprint, inner, panel, R)


def runs(mask):
    """A mask as [v, u_begin, u_end) runs."""
    out = []
    for v in np.nonzero(mask.any(axis=1))[0]:
        row = np.concatenate([[0], mask[v].astype(np.int8), [0]])
        edges = np.nonzero(np.diff(row))[0]
        out += [[int(v), int(s), int(e)] for s, e in zip(edges[::2], edges[1::2])]
    return out


def make(out, sc, frames):
    t0 = time.time()
    rng = np.random.default_rng(zlib.crc32(sc.name.encode()))
    b = build(sc, rng)
    fx, fy, ppx, ppy = sc.intrinsics
    fb = fx * BASELINE_M
    idx = np.flatnonzero(b.z.ravel() > 0)
    d0 = (fb / b.z.ravel()[idx]).astype(np.float32)  # d = f·B/Z
    hp = b.hole_p.ravel()[idx].astype(np.float32)
    max_count = 65535
    inner_idx, foot_idx = np.flatnonzero(b.inner.ravel()), np.flatnonzero(b.footprint.ravel())
    samples, holes = [], {"inner": 0, "footprint": 0}
    sigma = np.float32(sc.sigma_px)

    def frame(i):
        d = d0 + np.float32(sc.disparity_offset_px) + sigma * rng.standard_normal(
            d0.size, dtype=np.float32)
        d = np.round(d * 32.0) / 32.0  # 1/32 px subpixel step
        keep = (d > 0) & (rng.random(d0.size, dtype=np.float32) >= hp)
        counts = np.zeros(H * W, np.uint16)
        c = np.rint(fb / d[keep] / sc.depth_units_m)
        counts[idx[keep]] = np.where(c <= max_count, c, 0).astype(np.uint16)
        ci = counts[inner_idx]
        samples.append(ci[ci > 0])
        holes["inner"] += int((ci == 0).sum())
        holes["footprint"] += int((counts[foot_idx] == 0).sum())
        return counts.reshape(H, W)

    path = os.path.join(out, sc.name + ".bag")
    if os.path.exists(path):
        os.remove(path)
    cam = rs_record.Camera(W, H, fx, fy, ppx, ppy, sc.depth_units_m, BASELINE_M)
    rs_record.record(path, frame, frames, cam, 3 if sc.preset == "HA" else 4, sc.emitter,
                     sc.compress)

    valid = np.concatenate(samples)
    if valid.size == 0:
        raise RuntimeError("%s: no valid panel sample" % sc.name)
    median_m = float(np.median(valid.astype(np.float64))) * sc.depth_units_m
    c = b.R.T @ b.panel.c  # camera frame
    n = b.R.T @ b.panel.n
    # Expected error of a plane fitted to the valid samples: slope σ = σ_Z / (σ_x·√N), σ_x =
    # 1 m/√12 over the panel, σ_Z = Z²·σ_d/(f·B), σ_d with the 1/32 px step's own variance.
    sigma_d = math.sqrt(sc.sigma_px ** 2 + (1 / 32) ** 2 / 12)
    sigma_z = median_m ** 2 * sigma_d / fb
    tilt_sigma_deg = math.degrees(sigma_z / (PANEL_SIZE_M / math.sqrt(12) * math.sqrt(valid.size)))
    truth = dict(
        bag=sc.name + ".bag", scene=asdict(sc), frames=frames, preset=sc.preset,
        emitter="on" if sc.emitter else "off", distance_m=sc.distance_m,
        angle_deg=sc.angle_deg, light=sc.light, fx=fx, fy=fy, ppx=ppx, ppy=ppy,
        baseline_m=BASELINE_M, depth_units_m=sc.depth_units_m, noise_px=sc.sigma_px,
        camera_height_m=CAMERA_HEIGHT_M, panel_bottom_above_grass_m=PANEL_BOTTOM_M,
        post_width_m=POST_WIDTH_M, hedge_distance_m=HEDGE_DISTANCE_M, bush=BUSH if
        sc.bush_deg is not None else None,
        person=dict(PERSON, gap_m=sc.person_gap_m, side=sc.person) if sc.person else None,
        hole_rates=dict(HOLES[sc.preset], panel=panel_holes(sc)),
        true_median_depth_m=median_m,
        true_hole_rate_pct=100.0 * holes["inner"] / (inner_idx.size * frames),
        footprint_hole_rate_pct=100.0 * holes["footprint"] / (foot_idx.size * frames),
        valid_samples=int(valid.size), inner_px=int(inner_idx.size),
        footprint_px=int(foot_idx.size),
        range_m=float(np.linalg.norm(c)),
        azimuth_deg=math.degrees(math.atan2(c[0], c[2])),
        elevation_deg=math.degrees(math.atan2(-c[1], math.hypot(c[0], c[2]))),
        normal_tilt_deg=math.degrees(math.acos(min(1.0, abs(n[2])))),
        tilt_sigma_deg=tilt_sigma_deg, panel_width_m=PANEL_SIZE_M, panel_height_m=PANEL_SIZE_M,
        panel_center_m=[float(x) for x in c], panel_normal=[float(x) for x in n],
        footprint_runs=runs(b.footprint),
        object_runs={k: runs(b.label == LABELS[k]) for k in ("post", "bush", "person")},
        valid_pct_by_surface={k: float(100 * (1 - b.hole_p[b.label == v].mean()))
                              for k, v in LABELS.items() if k != "sky" and (b.label == v).any()},
        seconds=time.time() - t0)
    write(os.path.join(out, sc.name + ".truth.json"), json.dumps(truth, separators=(",", ":")))
    return truth


def write(path, text):
    with open(path + ".tmp", "w") as f:
        f.write(text)
    os.replace(path + ".tmp", path)


def make_or_keep(job):
    out, sc, frames, stamp = job
    truth_file = os.path.join(out, sc.name + ".truth.json")
    if (os.path.exists(os.path.join(out, sc.name + ".bag")) and os.path.exists(truth_file)
            and os.path.getmtime(truth_file) > stamp):
        with open(truth_file) as f:  # written by this version of the script
            truth = json.load(f)
        if truth["frames"] == frames:
            return truth, False
    return make(out, sc, frames), True


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("out", nargs="?")
    ap.add_argument("--only")
    ap.add_argument("--frames", type=int, default=0)
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--list", action="store_true")
    args = ap.parse_args()
    all_scenes = scenes()
    if args.list:
        print("\n".join(sc.name for sc in all_scenes))
        return 0
    if not args.out:
        ap.error("OUT_DIR is needed")
    chosen = [sc for sc in all_scenes if not args.only or sc.name == args.only]
    if not chosen:
        ap.error("no scene named %s (see --list)" % args.only)
    os.makedirs(args.out, exist_ok=True)
    stamp = max(os.path.getmtime(os.path.abspath(__file__)),
                os.path.getmtime(os.path.join(HERE, "rs_record.py")))
    jobs = [(args.out, sc, args.frames or sc.frames, stamp) for sc in chosen]
    t0 = time.time()
    if args.jobs > 1:
        with multiprocessing.get_context("spawn").Pool(args.jobs) as pool:
            results = pool.map(make_or_keep, jobs, chunksize=1)
    else:
        results = [make_or_keep(j) for j in jobs]
    for (truth, made), sc in zip(results, chosen):
        print("%-22s %2d frames, panel %5.1f%% holes, median %7.3f m%s" % (
            sc.name, truth["frames"], truth["true_hole_rate_pct"], truth["true_median_depth_m"],
            ", %.1fs" % truth["seconds"] if made else " (kept)"), flush=True)
    rows = ["bag,distance_m,angle_deg,light,preset,emitter"]
    rows += ["%s.bag,%g,%g,%s,%s,%s" % (sc.name, sc.distance_m, sc.angle_deg, sc.light, sc.preset,
                                        "on" if sc.emitter else "off") for sc in all_scenes]
    write(os.path.join(args.out, "manifest.csv"), "\n".join(rows) + "\n")
    boxes = {}
    for sc in all_scenes:  # a box inside each panel, as a careful hand draws it (box mode)
        truth_file = os.path.join(args.out, sc.name + ".truth.json")
        if os.path.exists(truth_file):
            with open(truth_file) as f:
                footprint = np.zeros((H, W), bool)
                for v, u0, u1 in json.load(f)["footprint_runs"]:
                    footprint[v, u0:u1] = True
            boxes[sc.name + ".bag"] = inner_box(footprint, margin=2)
    write(os.path.join(args.out, "boxes.json"), json.dumps(boxes, indent=1) + "\n")
    print("%d recordings in %.1f s" % (len(chosen), time.time() - t0))
    return 0


if __name__ == "__main__":
    sys.exit(main())
