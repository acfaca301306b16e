#!/usr/bin/env python3
"""Benchmark: frames per second reading every depth frame of a 300-frame 1280x720 bag,
uncompressed and LZ4-compressed, with depthbias's BagReader (bag_info --read-all) and with
librealsense's own playback (pyrealsense2, non-real-time), side by side on the same files.
Both read through rosbag: BagReader through Debian's rosbag_storage (and its roslz4 for LZ4
chunks), librealsense through the copy of rosbag it bundles.

The bags are recorded by librealsense's recorder from a software device (a noisy plane with
holes, like a real depth image), so both readers see the layout the camera writes. Each reader
runs REPEAT times on a warm page cache; the best run counts. Also prints the peak resident memory
of bag_info reading the whole bag (it holds one chunk and rosbag's index, a few tens of bytes
per message, so it grows only slowly with the bag's length).

Usage: scripts/bench_bag_read.py [--bin build/apps] [--frames 300] [--repeat 5] [--keep DIR]
"""
import argparse
import json
import os
import re
import resource
import shutil
import subprocess
import sys
import tempfile
import time

import numpy as np
import pyrealsense2 as rs

W, H = 1280, 720


def record(path, frames, compress):
    """Records `frames` depth frames with librealsense's recorder."""
    dev = rs.software_device()
    dev.register_info(rs.camera_info.name, "Intel RealSense D455")
    dev.register_info(rs.camera_info.serial_number, "000000000300")
    sensor = dev.add_sensor("Stereo Module")
    intr = rs.intrinsics()
    intr.width, intr.height = W, H
    intr.fx, intr.fy, intr.ppx, intr.ppy = 640.0, 640.0, 639.5, 359.5
    intr.model = rs.distortion.brown_conrady
    intr.coeffs = [0, 0, 0, 0, 0]
    vs = rs.video_stream()
    vs.type, vs.index, vs.uid = rs.stream.depth, 0, 0
    vs.width, vs.height, vs.fps, vs.bpp, vs.fmt = W, H, 30, 2, rs.format.z16
    vs.intrinsics = intr
    prof = sensor.add_video_stream(vs, True)
    sensor.add_read_only_option(rs.option.depth_units, 0.001)
    sensor.add_read_only_option(rs.option.visual_preset, 3)
    rec = rs.recorder(path, dev, compress)
    q = rs.frame_queue(4)
    sensor.open(prof)
    sensor.start(q)
    rng = np.random.default_rng(7)
    v, u = np.mgrid[0:H, 0:W]
    plane = 4000.0 + 0.4 * (u - W / 2) + 0.2 * (v - H / 2)
    for i in range(frames):
        img = plane + rng.normal(0.0, 15.0, size=plane.shape)
        img[rng.random(plane.shape) < 0.05] = 0
        img = img.astype(np.uint16)
        f = rs.software_video_frame()
        f.pixels, f.stride, f.bpp = img, 2 * W, 2
        f.timestamp, f.frame_number = 1000.0 + 33.3333 * i, i + 1
        f.domain = rs.timestamp_domain.hardware_clock
        f.depth_units = 0.001
        f.profile = prof.as_video_stream_profile()
        sensor.on_video_frame(f)
        while q.poll_for_frame():  # keep the queue empty
            pass
        time.sleep(0.02)
    time.sleep(0.5)
    sensor.stop()
    sensor.close()
    del rec


def cpu_seconds(who):
    r = resource.getrusage(who)
    return r.ru_utime + r.ru_stime


def ours(bin_dir, path):
    """Frames, wall seconds, CPU seconds (all threads) of bag_info --read-all."""
    cpu0 = cpu_seconds(resource.RUSAGE_CHILDREN)
    out = subprocess.run([os.path.join(bin_dir, "bag_info"), path, "--json", "--read-all"],
                         check=True, capture_output=True, text=True).stdout
    cpu = cpu_seconds(resource.RUSAGE_CHILDREN) - cpu0
    r = json.loads(out)["read_all"]
    return r["frames"], r["seconds"], cpu


def ours_peak_rss_kb(bin_dir, path):
    res = subprocess.run(["/usr/bin/time", "-v", os.path.join(bin_dir, "bag_info"), path,
                          "--read-all"], capture_output=True, text=True)
    m = re.search(r"Maximum resident set size \(kbytes\): (\d+)", res.stderr)
    return int(m.group(1)) if m else -1


def librealsense(path, frames_expected):
    """Non-real-time playback of every depth frame; the callback touches each frame's pixels."""
    done = []
    cpu0 = cpu_seconds(resource.RUSAGE_SELF)
    start = time.perf_counter()
    ctx = rs.context()
    dev = ctx.load_device(path)
    pb = dev.as_playback()
    pb.set_real_time(False)
    sensor = dev.first_depth_sensor()
    prof = [p for p in sensor.get_stream_profiles() if p.stream_type() == rs.stream.depth][0]
    checksum = [0]

    def on_frame(f):
        checksum[0] += int(np.asanyarray(f.get_data())[H // 2, W // 2])
        done.append(time.perf_counter())

    sensor.open(prof)
    sensor.start(on_frame)
    deadline = time.time() + 600
    while len(done) < frames_expected and time.time() < deadline:
        if pb.current_status() == rs.playback_status.stopped and done and \
                time.perf_counter() - done[-1] > 2.0:
            break
        time.sleep(0.001)
    end = done[-1] if done else time.perf_counter()
    cpu = cpu_seconds(resource.RUSAGE_SELF) - cpu0
    n = len(done)
    sensor.stop()
    sensor.close()
    return n, end - start, cpu


def main():
    ap = argparse.ArgumentParser()
    here = os.path.dirname(os.path.abspath(__file__))
    ap.add_argument("--bin", default=os.path.join(here, "..", "build", "apps"))
    ap.add_argument("--frames", type=int, default=300)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--keep", help="folder to record into and keep (default: a temp folder)")
    args = ap.parse_args()
    work = args.keep or tempfile.mkdtemp(prefix="bench_bag_read_")
    os.makedirs(work, exist_ok=True)
    rows = []
    try:
        for compress in (False, True):
            name = "bench_%dx%d_%d_%s.bag" % (W, H, args.frames, "lz4" if compress else "none")
            path = os.path.join(work, name)
            if not os.path.exists(path):
                record(path, args.frames, compress)
            with open(path, "rb") as f:  # warm the page cache for both readers
                while f.read(1 << 24):
                    pass
            best_ours, best_rs = None, None
            for _ in range(args.repeat):
                r = ours(args.bin, path)
                best_ours = r if best_ours is None or r[1] < best_ours[1] else best_ours
                r = librealsense(path, best_ours[0])
                best_rs = r if best_rs is None or r[1] < best_rs[1] else best_rs
            rss = ours_peak_rss_kb(args.bin, path)
            rows.append((name, os.path.getsize(path), best_ours, best_rs, rss))
    finally:
        if not args.keep:
            shutil.rmtree(work, ignore_errors=True)

    print("%-30s %6s %17s %18s %6s %21s %9s" %
          ("bag", "MB", "depthbias fr/s", "librealsense fr/s", "ratio", "CPU ms/frame (d / l)",
           "peak RSS"))
    for name, size, (n1, s1, c1), (n2, s2, c2), rss in rows:
        f1, f2 = n1 / s1, n2 / s2
        print("%-30s %6.1f %11.1f (%3d) %11.1f (%3d) %6.2f %10.2f / %-8.2f %6.1f MB" %
              (name, size / 1e6, f1, n1, f2, n2, f1 / f2, 1e3 * c1 / n1, 1e3 * c2 / n2,
               rss / 1024.0))
    print("frames/s over the whole read (open included), best of %d; (n) = frames delivered;"
          " ratio = depthbias / librealsense" % args.repeat)
    print("machine: %d cores, load average %.1f %.1f %.1f (other work slows both readers)" %
          ((os.cpu_count() or 0,) + tuple(os.getloadavg())))
    print("CPU ms/frame: user+system time of all the reader's threads per frame (d = depthbias,"
          " l = librealsense with its Python callback)")
    ok = all(n1 == n2 == args.frames for _, _, (n1, _, _), (n2, _, _), _ in rows)
    if not ok:
        print("warning: a reader did not deliver every frame", file=sys.stderr)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
