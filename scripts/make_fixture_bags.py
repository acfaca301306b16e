#!/usr/bin/env python3
"""Writes the small RealSense bags in tests/data/bags/ with librealsense's own recorder.

Each bag is recorded from a pyrealsense2 (2.56.5) software device: a "Stereo Module" depth
sensor with known intrinsics, read-only options and a few 16-bit depth frames of known pixels,
and, for one bag, an infrared stream, a color sensor and a motion (accel) sensor too. Next to each
bag goes <name>.truth.json with everything the generator put in: intrinsics, depth units,
options (as the float32 values librealsense stores), device info, and every depth frame's
number, timestamp and pixels. The script then plays each bag back with pyrealsense2 and checks
that librealsense reads the same back.

Usage: scripts/make_fixture_bags.py [OUT_DIR]   (default tests/data/bags)
"""
import importlib.metadata
import json
import os
import sys
import time

import numpy as np
import pyrealsense2 as rs

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from check_playback import play  # noqa: E402  (librealsense playback of a bag)

F32 = lambda v: float(np.float32(v))  # the value librealsense stores (options, units: float)

DEVICE_INFO = {
    rs.camera_info.name: "Intel RealSense D455",
    rs.camera_info.serial_number: "213522250123",
    rs.camera_info.firmware_version: "5.16.0.1",
    rs.camera_info.product_id: "0B5C",
    rs.camera_info.product_line: "D400",
}

FIXTURES = [
    # name, compressed, depth units, size, row padding [bytes], distortion, options, extras
    dict(name="d455_depth_1mm", compress=False, units=0.001, size=(64, 48), pad=0,
         model=rs.distortion.brown_conrady, coeffs=[-0.0561, 0.0673, -0.0004, 0.0007, -0.0213],
         options={rs.option.visual_preset: 3, rs.option.emitter_enabled: 1,
                  rs.option.laser_power: 150, rs.option.stereo_baseline: 95.07,
                  rs.option.depth_units: 0.001},
         frames=4, extras=False),
    dict(name="d455_depth_100um_lz4", compress=True, units=0.0001, size=(64, 48), pad=0,
         model=rs.distortion.inverse_brown_conrady, coeffs=[0.011, -0.021, 0.0012, -0.0008, 0.003],
         options={rs.option.visual_preset: 4, rs.option.emitter_enabled: 0,
                  rs.option.laser_power: 0, rs.option.depth_units: 0.0001},
         frames=3, extras=False),
    dict(name="d455_depth_color_imu_lz4", compress=True, units=0.001, size=(48, 32), pad=16,
         model=rs.distortion.brown_conrady, coeffs=[0, 0, 0, 0, 0],
         options={rs.option.visual_preset: 3, rs.option.emitter_enabled: 1,
                  rs.option.laser_power: 360, rs.option.depth_units: 0.001},
         frames=3, extras=True),
    dict(name="d455_depth_color_imu", compress=False, units=0.0001, size=(48, 32), pad=16,
         model=rs.distortion.brown_conrady, coeffs=[0.05, -0.06, 0.001, 0.002, 0.02],
         options={rs.option.visual_preset: 4, rs.option.emitter_enabled: 1,
                  rs.option.laser_power: 240, rs.option.depth_units: 0.0001},
         frames=3, extras=True),
]


def depth_pixels(w, h, i, salt):
    """Known pixels: a ramp with holes (0) on a diagonal pattern, different per frame."""
    u = np.arange(w)[None, :]
    v = np.arange(h)[:, None]
    img = (1000 + salt * 977 + 7 * u + 131 * v + 1009 * i) % 65535 + 1
    img[(u + 2 * v + i) % 13 == 0] = 0
    img[0, 0] = 65535  # the largest count survives the round trip
    return img.astype(np.uint16)


def intrinsics(w, h, model, coeffs, fx):
    it = rs.intrinsics()
    it.width, it.height = w, h
    it.fx, it.fy = fx, fx * 1.003
    it.ppx, it.ppy = w / 2 - 0.37, h / 2 + 0.61
    it.model = model
    it.coeffs = list(coeffs)
    return it


def record(path, fx, salt):
    w, h = fx["size"]
    dev = rs.software_device()
    for key, value in DEVICE_INFO.items():
        dev.register_info(key, value)
    depth = dev.add_sensor("Stereo Module")
    d_intr = intrinsics(w, h, fx["model"], fx["coeffs"], 0.625 * w)
    vs = rs.video_stream()
    vs.type, vs.index, vs.uid = rs.stream.depth, 0, 0
    vs.width, vs.height, vs.fps, vs.bpp, vs.fmt = w, h, 30, 2, rs.format.z16
    vs.intrinsics = d_intr
    d_prof = depth.add_video_stream(vs, True)
    for opt, value in fx["options"].items():
        depth.add_read_only_option(opt, value)
    extras = fx["extras"]
    if extras:
        ir = rs.video_stream()
        ir.type, ir.index, ir.uid = rs.stream.infrared, 1, 1
        ir.width, ir.height, ir.fps, ir.bpp, ir.fmt = w, h, 30, 1, rs.format.y8
        ir.intrinsics = d_intr
        ir_prof = depth.add_video_stream(ir)
        color = dev.add_sensor("RGB Camera")
        cs = rs.video_stream()
        cs.type, cs.index, cs.uid = rs.stream.color, 0, 2
        cs.width, cs.height, cs.fps, cs.bpp, cs.fmt = 2 * w, 2 * h, 30, 3, rs.format.rgb8
        cs.intrinsics = intrinsics(2 * w, 2 * h, rs.distortion.inverse_brown_conrady,
                                   [0.1, -0.2, 0.001, 0.0, 0.05], 1.2 * w)
        c_prof = color.add_video_stream(cs)
        color.add_read_only_option(rs.option.exposure, 156)
        motion = dev.add_sensor("Motion Module")
        ms = rs.motion_stream()
        ms.type, ms.index, ms.uid, ms.fps, ms.fmt = rs.stream.accel, 0, 3, 100, rs.format.motion_xyz32f
        m_prof = motion.add_motion_stream(ms)

    rec = rs.recorder(path, dev, fx["compress"])
    q = rs.frame_queue(64)
    if extras:
        depth.open([d_prof, ir_prof])
        color.open(c_prof)
        motion.open(m_prof)
        color.start(q)
        motion.start(q)
    else:
        depth.open(d_prof)
    depth.start(q)

    stride = 2 * w + fx["pad"]
    frames = []
    keep = []  # software frames must outlive the recorder's copy
    for i in range(fx["frames"]):
        ts = 1.0e6 + 33.3333 * i + 0.25 * salt
        img = depth_pixels(w, h, i, salt)
        buf = np.zeros((h, stride), dtype=np.uint8)
        buf[:, : 2 * w] = img.view(np.uint8).reshape(h, 2 * w)
        f = rs.software_video_frame()
        f.pixels, f.stride, f.bpp = buf, stride, 2
        f.timestamp, f.frame_number = ts, 100 + i
        f.domain = rs.timestamp_domain.hardware_clock
        f.depth_units = fx["units"]
        f.profile = d_prof.as_video_stream_profile()
        keep.append(buf)
        depth.on_video_frame(f)
        frames.append(dict(frame_number=100 + i, timestamp_ms=ts, pixels=img.flatten().tolist()))
        if extras:
            irimg = (np.arange(w * h, dtype=np.uint32) % 251).astype(np.uint8).reshape(h, w)
            g = rs.software_video_frame()
            g.pixels, g.stride, g.bpp = irimg, w, 1
            g.timestamp, g.frame_number = ts, 100 + i
            g.domain = rs.timestamp_domain.hardware_clock
            g.profile = ir_prof.as_video_stream_profile()
            keep.append(irimg)
            depth.on_video_frame(g)
            cimg = np.full((2 * h, 2 * w, 3), (10 * i) % 256, dtype=np.uint8)
            c = rs.software_video_frame()
            c.pixels, c.stride, c.bpp = cimg, 6 * w, 3
            c.timestamp, c.frame_number = ts + 1.0, 200 + i
            c.domain = rs.timestamp_domain.hardware_clock
            c.profile = c_prof.as_video_stream_profile()
            keep.append(cimg)
            color.on_video_frame(c)
            m = rs.software_motion_frame()
            m.data = rs.vector()
            m.data.x, m.data.y, m.data.z = 0.1, -9.8, 0.2
            m.timestamp, m.frame_number = ts + 2.0, 300 + i
            m.domain = rs.timestamp_domain.hardware_clock
            m.profile = m_prof.as_motion_stream_profile()
            motion.on_motion_frame(m)
        time.sleep(0.1)  # let the recorder write each frame before the next
    time.sleep(0.3)
    sensors = [depth] + ([color, motion] if extras else [])
    for s in sensors:
        s.stop()
    for s in sensors:
        s.close()
    del rec
    del keep

    names = {str(k).split(".")[-1]: v for k, v in DEVICE_INFO.items()}
    return dict(
        file=os.path.basename(path),
        recorder="pyrealsense2 %s software_device + rs.recorder" %
        importlib.metadata.version("pyrealsense2"),
        compressed=fx["compress"],
        depth_units=F32(fx["units"]),
        intrinsics=dict(width=w, height=h, fx=F32(d_intr.fx), fy=F32(d_intr.fy),
                        ppx=F32(d_intr.ppx), ppy=F32(d_intr.ppy), model=str(d_intr.model),
                        coeffs=[F32(c) for c in d_intr.coeffs]),
        row_stride_bytes=stride,
        options={option_name(o): F32(v)
                 for o, v in fx["options"].items()},
        device={"Name": DEVICE_INFO[rs.camera_info.name],
                "Serial Number": DEVICE_INFO[rs.camera_info.serial_number],
                "Firmware Version": DEVICE_INFO[rs.camera_info.firmware_version]},
        streams=(["Depth_0", "Infrared_1", "Color_0", "Accel_0"] if extras else ["Depth_0"]),
        frames=frames,
    )


def option_name(opt):
    """Name as the recorder writes it in topics (rs2_option_to_string with '_' for ' ')."""
    return str(opt).replace(" ", "_")


def check_playback(path, truth):
    """Plays the bag back with librealsense and compares with the truth."""
    got, _, _, intr = play(path, len(truth["frames"]))
    assert len(got) == len(truth["frames"]), (path, len(got))
    for (num, ts, img, units), t in zip(got, truth["frames"]):
        assert num == t["frame_number"] and abs(ts - t["timestamp_ms"]) < 1e-3, (num, ts)
        assert np.array_equal(img.flatten(), np.array(t["pixels"], dtype=np.uint16)), path
        assert units == truth["depth_units"], (units, truth["depth_units"])
    assert abs(intr.fx - truth["intrinsics"]["fx"]) < 1e-4


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(
        os.path.dirname(os.path.abspath(__file__)), "..", "tests", "data", "bags")
    os.makedirs(out, exist_ok=True)
    for salt, fx in enumerate(FIXTURES):
        path = os.path.join(out, fx["name"] + ".bag")
        if os.path.exists(path):
            os.remove(path)
        truth = record(path, fx, salt)
        check_playback(path, truth)
        with open(os.path.join(out, fx["name"] + ".truth.json"), "w") as f:
            json.dump(truth, f, separators=(",", ":"))
            f.write("\n")
        print("%s: %d bytes, %d frames" % (path, os.path.getsize(path), len(truth["frames"])))


if __name__ == "__main__":
    main()
