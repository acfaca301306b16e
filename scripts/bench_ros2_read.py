#!/usr/bin/env python3
"""Benchmark: frames per second reading every depth frame of the same 300 frames (1280x720)
from a ROS 1 bag with LZ4 chunks (librealsense's recorder) and from rosbag2 MCAP files with zstd
and lz4 chunks (the `mcap` + `mcap-ros2-support` packages' writer, 1 MiB chunks: one frame
each), all read by depthbias in one run (bag_info --read-all: open, decompress, decode every
frame). The frames are bench_bag_read.py's (a noisy plane with 5 % holes, seed 7); the readers'
checksums must agree. Each file is read REPEAT times on a warm page cache, alternating; the best
run counts. Also the peak resident memory of each read.

Usage: scripts/bench_ros2_read.py [--bin build/apps] [--frames 300] [--repeat 5] [--keep DIR]
"""
import argparse
import os
import shutil
import sys
import tempfile

import numpy as np

import bench_bag_read as b1
import make_ros2_fixtures as fx


def frames(n):
    """bench_bag_read.record's frames, in its order (the same generator and seed)."""
    rng = np.random.default_rng(7)
    v, u = np.mgrid[0:b1.H, 0:b1.W]
    plane = 4000.0 + 0.4 * (u - b1.W / 2) + 0.2 * (v - b1.H / 2)
    for _ in range(n):
        img = plane + rng.normal(0.0, 15.0, size=plane.shape)
        img[rng.random(plane.shape) < 0.05] = 0
        yield img.astype(np.uint16)


def write_mcap(path, n, compression):
    from mcap.writer import CompressionType
    from mcap_ros2.writer import Writer
    kind = {"zstd": CompressionType.ZSTD, "lz4": CompressionType.LZ4}[compression]
    with open(path + ".part", "wb") as f:
        w = Writer(f, compression=kind)
        image = w.register_msgdef("sensor_msgs/msg/Image", fx.IMAGE_DEF)
        info = w.register_msgdef("sensor_msgs/msg/CameraInfo", fx.INFO_DEF)
        for i, img in enumerate(frames(n)):
            t, st = fx.stamp(i)
            header = {"stamp": st, "frame_id": "camera_depth_optical_frame"}
            w.write_message(fx.INFO, info, dict(
                header=header, height=b1.H, width=b1.W, distortion_model="plumb_bob",
                d=[0.0] * 5, k=[640.0, 0, 639.5, 0, 640.0, 359.5, 0, 0, 1],
                r=[1, 0, 0, 0, 1, 0, 0, 0, 1],
                p=[640.0, 0, 639.5, 0, 0, 640.0, 359.5, 0, 0, 0, 1, 0],
                binning_x=0, binning_y=0, roi={"x_offset": 0, "y_offset": 0, "height": 0,
                                               "width": 0, "do_rectify": False}), log_time=t)
            w.write_message(fx.DEPTH, image, {
                "header": header, "height": b1.H, "width": b1.W, "encoding": "16UC1",
                "is_bigendian": 0, "step": 2 * b1.W, "data": img.tobytes()}, log_time=t)
        w.finish()
    os.rename(path + ".part", path)


def main():
    ap = argparse.ArgumentParser()
    here = os.path.dirname(os.path.abspath(__file__))
    ap.add_argument("--bin", default=os.path.join(here, "..", "build", "apps"))
    ap.add_argument("--frames", type=int, default=300)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--keep", help="folder to write into and keep (default: a temp folder)")
    args = ap.parse_args()
    work = args.keep or tempfile.mkdtemp(prefix="bench_ros2_read_")
    os.makedirs(work, exist_ok=True)
    stem = "bench_%dx%d_%d" % (b1.W, b1.H, args.frames)
    files = [("ROS 1 bag, LZ4 chunks", stem + "_lz4.bag"),
             ("rosbag2 MCAP, zstd chunks", stem + "_zstd.mcap"),
             ("rosbag2 MCAP, lz4 chunks", stem + "_lz4.mcap")]
    rows = []
    try:
        for _, name in files:
            path = os.path.join(work, name)
            if os.path.exists(path):
                continue
            if name.endswith(".bag"):
                b1.record(path, args.frames, True)
            else:
                write_mcap(path, args.frames, name.rsplit("_", 1)[1].split(".")[0])
        for _, name in files:  # warm the page cache
            with open(os.path.join(work, name), "rb") as f:
                while f.read(1 << 24):
                    pass
        best = {}
        for _ in range(args.repeat):
            for _, name in files:
                r = b1.ours(args.bin, os.path.join(work, name))
                if name not in best or r[1] < best[name][1]:
                    best[name] = r
        checksums = set()
        for label, name in files:
            path = os.path.join(work, name)
            out = b1.subprocess.run([os.path.join(args.bin, "bag_info"), path, "--json",
                                     "--read-all"], check=True, capture_output=True,
                                    text=True).stdout
            checksums.add(b1.json.loads(out)["read_all"]["checksum"])
            rows.append((label, name, os.path.getsize(path), best[name],
                         b1.ours_peak_rss_kb(args.bin, path)))
    finally:
        if not args.keep:
            shutil.rmtree(work, ignore_errors=True)
    print("%-28s %-34s %7s %12s %14s %9s" %
          ("recording", "file", "MB", "frames/s", "CPU ms/frame", "peak RSS"))
    for label, name, size, (n, s, cpu), rss in rows:
        print("%-28s %-34s %7.1f %6.1f (%3d) %14.2f %6.1f MB" %
              (label, name, size / 1e6, n / s, n, 1e3 * cpu / n, rss / 1024.0))
    ros1 = rows[0][3][0] / rows[0][3][1]
    zstd = rows[1][3][0] / rows[1][3][1]
    print("MCAP zstd / ROS 1 LZ4: %.2f (frames/s over the whole read, open included, best of %d)"
          % (zstd / ros1, args.repeat))
    print("machine: %d cores, load average %.1f %.1f %.1f (other work slows every reader)" %
          ((os.cpu_count() or 0,) + tuple(os.getloadavg())))
    ok = len(checksums) == 1 and all(r[3][0] == args.frames for r in rows)
    if not ok:
        print("warning: the readers disagree (checksums %s)" % sorted(checksums), file=sys.stderr)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
