"""Records depth frames into a RealSense bag with librealsense's own recorder (pyrealsense2
software device), as a D455's depth stream: z16 at 30 f/s, the given intrinsics (Brown-Conrady,
no distortion), depth units, and the read-only options Visual_Preset, Emitter_Enabled and
Stereo_Baseline that panel_extract reads back.

Used by make_panel_bags.py and make_field_bags.py.
"""
import time
from dataclasses import dataclass

import pyrealsense2 as rs


@dataclass
class Camera:
    """Depth stream of the recording: size [px], focal lengths and principal point [px], depth
    units [m per count], stereo baseline [m]."""
    width: int = 1280
    height: int = 720
    fx: float = 640.0
    fy: float = 640.0
    ppx: float = 640.0
    ppy: float = 360.0
    depth_units_m: float = 0.001
    baseline_m: float = 0.095


def record(path, frames_fn, n, cam, preset, emitter, compress):
    """Writes n frames, frames_fn(i) -> uint16 array (height x width) of depth counts, to path.
    preset: Visual_Preset code (3 = High Accuracy, 4 = High Density); emitter: 0 or 1;
    compress: LZ4 chunks if true."""
    dev = rs.software_device()
    dev.register_info(rs.camera_info.name, "Intel RealSense D455")
    dev.register_info(rs.camera_info.serial_number, "000000000455")
    dev.register_info(rs.camera_info.firmware_version, "5.16.0.1")
    depth = dev.add_sensor("Stereo Module")
    it = rs.intrinsics()
    it.width, it.height, it.fx, it.fy, it.ppx, it.ppy = (cam.width, cam.height, cam.fx, cam.fy,
                                                          cam.ppx, cam.ppy)
    it.model, it.coeffs = rs.distortion.brown_conrady, [0.0] * 5
    vs = rs.video_stream()
    vs.type, vs.index, vs.uid = rs.stream.depth, 0, 0
    vs.width, vs.height, vs.fps, vs.bpp, vs.fmt = cam.width, cam.height, 30, 2, rs.format.z16
    vs.intrinsics = it
    prof = depth.add_video_stream(vs, True)
    depth.add_read_only_option(rs.option.depth_units, cam.depth_units_m)
    depth.add_read_only_option(rs.option.visual_preset, preset)
    depth.add_read_only_option(rs.option.emitter_enabled, emitter)
    depth.add_read_only_option(rs.option.stereo_baseline, cam.baseline_m * 1000)
    rec = rs.recorder(path, dev, compress)
    depth.open(prof)
    depth.start(lambda f: None)
    keep = []
    for i in range(n):
        img = frames_fn(i)
        f = rs.software_video_frame()
        f.pixels, f.stride, f.bpp = img, 2 * cam.width, 2
        f.timestamp, f.frame_number = 1.0e6 + 1000.0 / 30 * i, i + 1
        f.domain = rs.timestamp_domain.hardware_clock
        f.depth_units = cam.depth_units_m
        f.profile = prof.as_video_stream_profile()
        keep.append(img)  # the software device reads the pixels after on_video_frame returns
        depth.on_video_frame(f)
        if len(keep) > 8:
            time.sleep(0.002)
            keep.pop(0)
    time.sleep(0.3)
    depth.stop()
    depth.close()
    del rec
