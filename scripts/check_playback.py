#!/usr/bin/env python3
"""Checks that librealsense plays back the bags depthbias's BagWriter writes.

Runs the write_test_bag helper (which writes bags with BagWriter and lists what it put in them
in written.json), then plays every bag with pyrealsense2 (non-real-time) and compares frames
(numbers, timestamps, every pixel), depth units, depth intrinsics, recorded options and device
info. Exits non-zero with one line per mismatch.

Usage: scripts/check_playback.py --writer PATH/write_test_bag --out DIR
"""
import argparse
import json
import os
import subprocess
import sys
import time

import numpy as np
import pyrealsense2 as rs


def test_pixels(w, h, i):
    """Same formula as TestPixel() in tests/io/write_test_bag.cpp."""
    u = np.arange(w)[None, :]
    v = np.arange(h)[:, None]
    img = (7 * u + 131 * v + 1009 * i) % 65535 + 1
    img[(u + 2 * v + i) % 13 == 0] = 0
    return img.astype(np.uint16)


def option_by_name(name):
    for o in dir(rs.option):
        if not o.startswith("_"):
            opt = getattr(rs.option, o)
            if isinstance(opt, rs.option) and str(opt).replace(" ", "_") == name:
                return opt
    raise KeyError(name)


def play(path, expected):
    """All depth frames of a bag, played by librealsense as fast as it can."""
    ctx = rs.context()
    dev = ctx.load_device(path)
    pb = dev.as_playback()
    pb.set_real_time(False)
    sensor = dev.first_depth_sensor()
    profile = [p for p in sensor.get_stream_profiles() if p.stream_type() == rs.stream.depth][0]
    got = []
    sensor.open(profile)
    sensor.start(lambda f: got.append((f.get_frame_number(), f.get_timestamp(),
                                       np.asanyarray(f.get_data()).copy(),
                                       f.as_depth_frame().get_units())))
    deadline = time.time() + 10.0
    while len(got) < expected and time.time() < deadline:
        time.sleep(0.01)
    time.sleep(0.2)
    sensor.stop()
    options = {}
    for opt in sensor.get_supported_options():
        options[str(opt).replace(" ", "_")] = sensor.get_option(opt)
    sensor.close()
    info = {k: dev.get_info(v) for k, v in (("Name", rs.camera_info.name),
                                            ("Serial Number", rs.camera_info.serial_number),
                                            ("Firmware Version", rs.camera_info.firmware_version))
            if dev.supports(v)}
    intr = profile.as_video_stream_profile().get_intrinsics()
    return got, options, info, intr


def check(path, truth):
    errors = []
    f32 = lambda v: float(np.float32(v))
    got, options, info, intr = play(path, len(truth["frames"]))
    name = os.path.basename(path)
    if len(got) != len(truth["frames"]):
        errors.append("%s: librealsense played %d frames, %d written" %
                      (name, len(got), len(truth["frames"])))
    t_in = truth["intrinsics"]
    for i, ((num, ts, img, units), t) in enumerate(zip(got, truth["frames"])):
        if num != t["frame_number"]:
            errors.append("%s frame %d: number %d, written %d" % (name, i, num, t["frame_number"]))
        if abs(ts - t["timestamp_ms"]) > 1e-3:
            errors.append("%s frame %d: timestamp %.6f, written %.6f" % (name, i, ts, t["timestamp_ms"]))
        want = test_pixels(t_in["width"], t_in["height"], i)
        if img.shape != want.shape or not np.array_equal(img, want):
            errors.append("%s frame %d: pixels differ" % (name, i))
        if units != f32(truth["depth_units"]):
            errors.append("%s frame %d: depth units %r, written %r" % (name, i, units, truth["depth_units"]))
    for key in ("width", "height"):
        if getattr(intr, key) != t_in[key]:
            errors.append("%s: intrinsics %s %r, written %r" % (name, key, getattr(intr, key), t_in[key]))
    for key in ("fx", "fy", "ppx", "ppy"):
        if getattr(intr, key) != f32(t_in[key]):
            errors.append("%s: intrinsics %s %r, written %r" % (name, key, getattr(intr, key), t_in[key]))
    if str(intr.model) != "distortion.brown_conrady":
        errors.append("%s: distortion model %s" % (name, intr.model))
    if [f32(c) for c in intr.coeffs] != [f32(c) for c in t_in["coeffs"]]:
        errors.append("%s: coeffs %r, written %r" % (name, intr.coeffs, t_in["coeffs"]))
    for key, value in truth["options"].items():
        if key not in options:
            errors.append("%s: option %s missing in playback" % (name, key))
        elif options[key] != f32(value):
            errors.append("%s: option %s = %r, written %r" % (name, key, options[key], value))
    for key, value in truth["device"].items():
        if info.get(key) != value:
            errors.append("%s: device %s = %r, written %r" % (name, key, info.get(key), value))
    print("%s: %d frames, %d options, intrinsics %dx%d fx %.3f: %s" %
          (name, len(got), len(options), intr.width, intr.height, intr.fx,
           "ok" if not errors else "MISMATCH"))
    return errors


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--writer", required=True)
    ap.add_argument("--out", required=True)
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    subprocess.run([args.writer, args.out], check=True)
    with open(os.path.join(args.out, "written.json")) as f:
        truths = json.load(f)
    errors = []
    for truth in truths:
        errors += check(os.path.join(args.out, truth["file"]), truth)
    for e in errors:
        print(e, file=sys.stderr)
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main())
