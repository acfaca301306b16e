#!/usr/bin/env python3
"""Speed and memory of panel_extract against two peers, side by side, on one recording.

The recordings: 300 frames of 1280x720 depth written by librealsense's recorder, the 8 m /
20 deg panel scene of make_panel_bags.py, once uncompressed (as the D455 records) and once LZ4
compressed. Every contender reads the same file, after one read to put it in the page cache.
Each runs in its own process, so its peak memory (ru_maxrss from wait4) is its own.

  panel_extract   the whole tool: read the bag, detect the panel, measure it, write the CSV;
                  the detection frames (30) are kept and measured, every frame read once
  ... read twice  the same with keep_detection_frames: false: the recording is read again from
                  the start to measure (the first 30 frames decompressed twice), for reference
  BagReader       depthbias's bag reader alone (bag_info --read-all, whole process): the floor
                  panel_extract stands on, for reference
  (a) playback    pyrealsense2 playback alone, non-real-time, every depth frame's data touched
  (b) python      pyrealsense2 playback + numpy deprojection + Open3D segment_plane twice per
                  frame (ground, then the panel in what is left); Open3D is installed here by
                  pip if missing (an optional benchmark dependency, not needed by the tests).
                  Run on the first --python-frames frames, frames/s from those.

Hole fill (lib/panel/hole_fill.h), OpenCV's (default) beside the four directional sweeps, on the
same inputs in one run: panel_extract with `hole_fill: opencv` and with `hole_fill: sweeps` on the
300-frame recording and, with --field-bags DIR (the bags of make_field_bags.py, e.g.
build/field_bags), on every field scene; the rows compared column by column (identical, or the
largest difference per column) and the wall times side by side. --hole-fill-only runs just that.

Targets: panel_extract >= 300 frames/s, no slower than (a), >= 20x faster than (b), peak
memory <= 500 MB.

Usage: bench_panel_extract.py [--bin build/apps] [--work build/bench_panel] [--frames 300]
                              [--python-frames 20] [--repeat 3] [--compression none|lz4|both]
                              [--no-python] [--field-bags DIR] [--hole-fill-only]
"""
import argparse
import json
import os
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))


def run(cmd):
    """Runs cmd under /usr/bin/time (so the peak RSS is the program's own, not inherited from
    this script by fork); returns (wall seconds, peak RSS MB, stdout)."""
    rss_file = os.path.join(os.environ.get("TMPDIR", "/tmp"), "bench_rss_%d.txt" % os.getpid())
    t0 = time.perf_counter()
    p = subprocess.run(["/usr/bin/time", "-f", "%M", "-o", rss_file] + cmd,
                       stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    wall = time.perf_counter() - t0
    if p.returncode != 0:
        sys.exit("failed: %s\n%s" % (" ".join(cmd), p.stderr.decode()))
    with open(rss_file) as f:
        rss_kb = float(f.read().split()[-1])
    os.remove(rss_file)
    return wall, rss_kb / 1024.0, p.stdout.decode()


def open_playback(path):
    """pyrealsense2 pipeline playing the file back as fast as it is read (non-real-time)."""
    import pyrealsense2 as rs
    pipe, cfg = rs.pipeline(), rs.config()
    cfg.enable_device_from_file(path, repeat_playback=False)
    prof = pipe.start(cfg)
    prof.get_device().as_playback().set_real_time(False)
    return pipe, prof


def peer_playback(path):
    import numpy as np
    t0 = time.perf_counter()  # from opening the file, as panel_extract's run does
    pipe, _ = open_playback(path)
    n, checksum, t_last = 0, 0, t0
    while True:
        ok, fs = pipe.try_wait_for_frames(1000)
        if not ok:
            break
        checksum += int(np.asanyarray(fs.get_depth_frame().get_data())[-1, 640])
        n += 1
        t_last = time.perf_counter()
    pipe.stop()
    print(json.dumps(dict(frames=n, seconds=t_last - t0, checksum=checksum)))


def peer_python(path, max_frames):
    import numpy as np
    import open3d as o3d
    import pyrealsense2 as rs
    t0 = time.perf_counter()
    pipe, prof = open_playback(path)
    intr = prof.get_stream(rs.stream.depth).as_video_stream_profile().get_intrinsics()
    u, v = np.meshgrid(np.arange(intr.width), np.arange(intr.height))
    rx = ((u - intr.ppx) / intr.fx).ravel()
    ry = ((v - intr.ppy) / intr.fy).ravel()
    n, panel_z = 0, []
    while n < max_frames:
        ok, fs = pipe.try_wait_for_frames(5000)
        if not ok:
            break
        d = fs.get_depth_frame()
        z = np.asanyarray(d.get_data()).ravel() * d.get_units()
        ok = z > 0
        pts = np.stack([rx[ok] * z[ok], ry[ok] * z[ok], z[ok]], axis=1)
        pcd = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(pts))
        _, ground = pcd.segment_plane(distance_threshold=0.08, ransac_n=3, num_iterations=100)
        rest = pcd.select_by_index(ground, invert=True)
        _, panel = rest.segment_plane(distance_threshold=0.1, ransac_n=3, num_iterations=100)
        panel_z.append(float(np.median(np.asarray(rest.points)[panel][:, 2])))
        n += 1
    t1 = time.perf_counter()
    pipe.stop()
    print(json.dumps(dict(frames=n, seconds=t1 - t0, median_z=float(np.median(panel_z)))))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--bin", default=os.path.join(HERE, "..", "build", "apps"))
    ap.add_argument("--work", default=os.path.join(HERE, "..", "build", "bench_panel"))
    ap.add_argument("--frames", type=int, default=300)
    ap.add_argument("--python-frames", type=int, default=20)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--compression", choices=["none", "lz4", "both"], default="both")
    ap.add_argument("--no-python", action="store_true", help="skip the Python + Open3D peer")
    ap.add_argument("--field-bags", help="field-scene bags (make_field_bags.py) for the hole fill")
    ap.add_argument("--hole-fill-only", action="store_true",
                    help="only the hole fill comparison (OpenCV beside the sweeps)")
    ap.add_argument("--peer", help=argparse.SUPPRESS)
    ap.add_argument("--file", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.peer == "playback":
        return peer_playback(args.file)
    if args.peer == "python":
        return peer_python(args.file, args.python_frames)

    os.makedirs(args.work, exist_ok=True)
    if not (args.no_python or args.hole_fill_only) and subprocess.call(
            [sys.executable, "-c", "import open3d"], stderr=subprocess.DEVNULL):
        print("bench: pip installing open3d (optional benchmark dependency)", flush=True)
        subprocess.check_call([sys.executable, "-m", "pip", "install", "-q",
                               "--disable-pip-version-check", "open3d"])
    kinds = ["none", "lz4"] if args.compression == "both" else [args.compression]
    ok = True
    if not args.hole_fill_only:
        for kind in kinds:
            ok &= bench_one(args, kind)
    bag = make_bench_bag(args, kinds[0])
    compare_hole_fill(args, "300-frame recording", [bag], None)
    if args.field_bags:
        bags = sorted(os.path.join(args.field_bags, f) for f in os.listdir(args.field_bags)
                      if f.endswith(".bag"))
        manifest = os.path.join(args.field_bags, "manifest.csv")
        compare_hole_fill(args, "field scenes (%d bags)" % len(bags), bags,
                          manifest if os.path.exists(manifest) else None)
    return 0 if ok else 1


def read_rows(path):
    import csv
    with open(path) as f:
        return {r["bag"]: r for r in csv.DictReader(f)}


def compare_hole_fill(args, what, bags, manifest):
    """panel_extract with hole_fill: opencv and sweeps on the same bags (one process each, best of
    --repeat wall times); the rows compared column by column."""
    work = os.path.join(args.work, "hole_fill")
    os.makedirs(work, exist_ok=True)
    tool = os.path.join(args.bin, "panel_extract")
    rows, times = {}, {}
    for method in ("opencv", "sweeps"):
        cfg = os.path.join(work, method + ".yaml")
        with open(cfg, "w") as f:
            f.write("hole_fill: %s\n" % method)
        out = os.path.join(work, "%s.csv" % method)
        cmd = [tool, "--quiet", "--config", cfg, "--out", out]
        if manifest:
            cmd += ["--manifest", manifest]
        best = None
        for _ in range(args.repeat):
            t0 = time.perf_counter()
            code = subprocess.call(cmd + bags, stdout=subprocess.DEVNULL,
                                   stderr=subprocess.DEVNULL)
            wall = time.perf_counter() - t0
            if code not in (0, 1):
                sys.exit("failed (%d): %s" % (code, " ".join(cmd)))
            best = wall if best is None else min(best, wall)
        rows[method], times[method] = read_rows(out), best
    a, b = rows["opencv"], rows["sweeps"]
    identical = sum(1 for k in a if k in b and a[k] == b[k])
    print("hole fill on the %s, %d cores, load %.1f, best of %d runs" %
          (what, os.cpu_count(), os.getloadavg()[0], args.repeat))
    print("%-28s %9s" % ("", "seconds"))
    print("%-28s %9.3f" % ("panel_extract, opencv", times["opencv"]))
    print("%-28s %9.3f   (%.2fx the OpenCV time)" % ("panel_extract, sweeps", times["sweeps"],
                                                   times["sweeps"] / times["opencv"]))
    print("rows identical: %d of %d" % (identical, len(a)))
    diffs = {}
    for k in a:
        if k not in b:
            continue
        for col, va in a[k].items():
            vb = b[k].get(col)
            if va == vb:
                continue
            try:
                d = abs(float(va) - float(vb))
            except (TypeError, ValueError):
                d = float("inf")
            if d > diffs.get(col, (0, ""))[0]:
                diffs[col] = (d, k)
    for col, (d, k) in sorted(diffs.items()):
        print("  %-18s max |opencv - sweeps| %.6g (%s)" % (col, d, k))
    print()


def make_bench_bag(args, kind):
    work = os.path.join(args.work, kind)
    os.makedirs(work, exist_ok=True)
    bag = os.path.join(work, "bench_panel.bag")
    truth_file = os.path.join(work, "bench_panel.truth.json")
    if not os.path.exists(truth_file) or json.load(open(truth_file))["frames"] != args.frames:
        cmd = [sys.executable, os.path.join(HERE, "make_panel_bags.py"), work, "--bench",
               str(args.frames)]
        if kind == "none":
            cmd.append("--uncompressed")
        subprocess.check_call(cmd)
    return bag


def best_of(n, cmd):
    best = None
    for _ in range(n):
        wall, rss, _ = run(cmd)
        best = min(best or (wall, rss), (wall, rss))
    return best


def bench_one(args, kind):
    work = os.path.join(args.work, kind)
    bag = make_bench_bag(args, kind)
    with open(bag, "rb") as f:  # page cache, the same for everyone
        while f.read(1 << 24):
            pass
    size_mb = os.path.getsize(bag) / 1e6
    out_csv = os.path.join(work, "metrics.csv")
    tool = os.path.join(args.bin, "panel_extract")
    twice_yaml = os.path.join(work, "read_twice.yaml")
    with open(twice_yaml, "w") as f:
        f.write("keep_detection_frames: false\n")

    rows = []
    wall, rss = best_of(args.repeat, [tool, "--quiet", "--out", out_csv, bag])
    rows.append(("panel_extract", args.frames, wall, rss))
    wall, rss = best_of(args.repeat, [tool, "--quiet", "--config", twice_yaml, "--out", out_csv,
                                      bag])
    rows.append(("panel_extract, read twice", args.frames, wall, rss))
    reader = os.path.join(args.bin, "bag_info")
    if os.path.exists(reader):  # the floor: depthbias's bag reader alone, no processing
        wall, rss = best_of(args.repeat, [reader, "--read-all", bag])
        rows.append(("io::BagReader alone", args.frames, wall, rss))
    best = None
    for _ in range(args.repeat):
        wall, rss, out = run([sys.executable, __file__, "--peer", "playback", "--file", bag])
        r = json.loads(out)
        if r["frames"] != args.frames:
            sys.exit("playback delivered %d of %d frames" % (r["frames"], args.frames))
        best = min(best or (r["seconds"], rss), (r["seconds"], rss))
    rows.append(("(a) pyrealsense2 playback", args.frames, best[0], best[1]))
    if not args.no_python:
        wall, rss, out = run([sys.executable, __file__, "--peer", "python", "--file", bag,
                              "--python-frames", str(args.python_frames)])
        r = json.loads(out)
        rows.append(("(b) python + open3d", r["frames"], r["seconds"], rss))

    fps = {name: n / s for name, n, s, _ in rows}
    tool_fps = fps["panel_extract"]
    print("recording: %s (%s, %d frames 1280x720, %.0f MB), %d cores, load %.1f, best of %d runs"
          % (bag, "LZ4" if kind == "lz4" else "uncompressed", args.frames, size_mb,
             os.cpu_count(), os.getloadavg()[0], args.repeat))
    print("%-28s %7s %9s %10s %12s %11s" % ("", "frames", "seconds", "frames/s",
                                            "tool speedup", "peak MB"))
    for name, n, s, mb in rows:
        print("%-28s %7d %9.3f %10.1f %11.1fx %11.0f" % (name, n, s, n / s, tool_fps / (n / s),
                                                          mb))
    checks = [
        ("panel_extract >= 300 frames/s", tool_fps >= 300),
        ("panel_extract no slower than (a)", tool_fps >= fps["(a) pyrealsense2 playback"]),
        ("panel_extract peak memory <= 500 MB", rows[0][3] <= 500),
    ]
    if not args.no_python:
        checks.append(("panel_extract >= 20x faster than (b)",
                       tool_fps >= 20 * fps["(b) python + open3d"]))
    for text, ok in checks:
        print("%-40s %s" % (text, "yes" if ok else "NO"))
    print()
    return all(ok for _, ok in checks)


if __name__ == "__main__":
    sys.exit(main())
