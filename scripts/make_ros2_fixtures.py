#!/usr/bin/env python3
"""Writes one panel scene as a RealSense ROS 1 bag and as rosbag2 recordings made by writers
depthbias did not write, plus damaged copies, for the ROS 2 reader's tests.

The scene is make_panel_bags.py's (the 1 x 1 m panel at 8 m, 20 deg, 30 % holes; its scene()
and render() with one seed), rendered once: the same depth frames go into
  ros1.bag              librealsense's recorder (rs_record.py), as make_panel_bags.py writes
  rosbags_mcap/         the `rosbags` package, rosbag2 folder, MCAP storage (with the
                        wrapper's /parameter_events: depth_module.visual_preset, emitter_enabled)
  rosbags_sqlite/       the `rosbags` package, rosbag2 folder, SQLite3 storage (no parameters:
                        the manifest gives preset and emitter)
  mcap_zstd.mcap        the `mcap` + `mcap-ros2-support` packages, zstd chunks
  mcap_lz4.mcap         the same, lz4 chunks
Topics as the RealSense ROS 2 wrapper names them: /camera/camera/depth/image_rect_raw
(sensor_msgs/msg/Image, 16UC1 millimetres), /camera/camera/depth/camera_info (plumb_bob).
Also manifest.csv (every recording with preset HA, emitter on), and damaged copies in bad/:
cut.mcap (mcap_zstd.mcap cut in its middle: no summary, no footer), flipped.mcap (a byte of a
chunk's compressed data changed), huge_record.mcap (a record length of 2^62), huge_chunk.mcap
(a chunk claiming 2^40 bytes uncompressed), huge_image.mcap (an image claiming 65535 x 65535 px
in 40 bytes), other_size.mcap (camera_info 32 x 24 px, images 16 x 12 px), notmcap.mcap
(text), cut.db3 (the SQLite file cut to half), garbage.db3.

Usage: make_ros2_fixtures.py OUT_DIR [--frames N]
       make_ros2_fixtures.py --check-mcap FILE.mcap FRAMES   (reads a file depthbias wrote with
       the mcap package's reader and decoder; prints what it found, exits 1 if not as expected)
"""
import argparse
import os
import shutil
import struct
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

DEPTH = "/camera/camera/depth/image_rect_raw"
INFO = "/camera/camera/depth/camera_info"
PARAMS = "/parameter_events"
T0_NS = 1_700_000_000_000_000_000
PERIOD_NS = 33_333_333

SEP = "=" * 80 + "\n"
HEADER_DEF = ("MSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id\n" + SEP +
              "MSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n")
IMAGE_DEF = ("std_msgs/Header header\nuint32 height\nuint32 width\nstring encoding\n"
             "uint8 is_bigendian\nuint32 step\nuint8[] data\n" + SEP + HEADER_DEF)
INFO_DEF = ("std_msgs/Header header\nuint32 height\nuint32 width\nstring distortion_model\n"
            "float64[] d\nfloat64[9] k\nfloat64[9] r\nfloat64[12] p\nuint32 binning_x\n"
            "uint32 binning_y\nsensor_msgs/RegionOfInterest roi\n" + SEP + HEADER_DEF + SEP +
            "MSG: sensor_msgs/RegionOfInterest\nuint32 x_offset\nuint32 y_offset\n"
            "uint32 height\nuint32 width\nbool do_rectify\n")


def scene_frames(n):
    import make_panel_bags as pb
    _, z, footprint = pb.scene(8, 20)
    rng = np.random.default_rng(7)
    return [pb.render(z, footprint, 0.30, rng) for _ in range(n)], pb


def stamp(i):
    t = T0_NS + i * PERIOD_NS
    return t, {"sec": t // 1_000_000_000, "nanosec": t % 1_000_000_000}


def info_fields(pb):
    return dict(height=pb.H, width=pb.W, distortion_model="plumb_bob", d=[0.0] * 5,
                k=[pb.FX, 0, pb.PPX, 0, pb.FX, pb.PPY, 0, 0, 1], r=[1, 0, 0, 0, 1, 0, 0, 0, 1],
                p=[pb.FX, 0, pb.PPX, 0, 0, pb.FX, pb.PPY, 0, 0, 0, 1, 0])


def write_rosbags(path, frames, pb, storage, with_params):
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore
    ts = get_typestore(Stores.ROS2_HUMBLE)
    T = ts.types
    plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
    with Writer(path, version=9, storage_plugin=plugin) as w:
        cd = w.add_connection(DEPTH, "sensor_msgs/msg/Image", typestore=ts)
        ci = w.add_connection(INFO, "sensor_msgs/msg/CameraInfo", typestore=ts)
        if with_params:
            cp = w.add_connection(PARAMS, "rcl_interfaces/msg/ParameterEvent", typestore=ts)
            t, st = stamp(0)

            def param(name, value):
                v = T["rcl_interfaces/msg/ParameterValue"](
                    type=2, bool_value=False, integer_value=value, double_value=0.0,
                    string_value="", byte_array_value=np.zeros(0, np.uint8),
                    bool_array_value=np.zeros(0, np.bool_),
                    integer_array_value=np.zeros(0, np.int64),
                    double_array_value=np.zeros(0, np.float64), string_array_value=[])
                return T["rcl_interfaces/msg/Parameter"](name=name, value=v)
            ev = T["rcl_interfaces/msg/ParameterEvent"](
                stamp=T["builtin_interfaces/msg/Time"](**st), node="/camera/camera",
                new_parameters=[param("depth_module.visual_preset", 3),
                                param("depth_module.emitter_enabled", 1)],
                changed_parameters=[], deleted_parameters=[])
            w.write(cp, t - 1000, ts.serialize_cdr(ev, "rcl_interfaces/msg/ParameterEvent"))
        for i, img in enumerate(frames):
            t, st = stamp(i)
            header = T["std_msgs/msg/Header"](stamp=T["builtin_interfaces/msg/Time"](**st),
                                             frame_id="camera_depth_optical_frame")
            f = info_fields(pb)
            info = T["sensor_msgs/msg/CameraInfo"](
                header=header, height=f["height"], width=f["width"],
                distortion_model=f["distortion_model"], d=np.array(f["d"], np.float64),
                k=np.array(f["k"], np.float64), r=np.array(f["r"], np.float64),
                p=np.array(f["p"], np.float64), binning_x=0, binning_y=0,
                roi=T["sensor_msgs/msg/RegionOfInterest"](x_offset=0, y_offset=0, height=0,
                                                          width=0, do_rectify=False))
            w.write(ci, t, ts.serialize_cdr(info, "sensor_msgs/msg/CameraInfo"))
            msg = T["sensor_msgs/msg/Image"](
                header=header, height=pb.H, width=pb.W, encoding="16UC1", is_bigendian=0,
                step=pb.W * 2, data=np.ascontiguousarray(img, "<u2").view(np.uint8).ravel())
            w.write(cd, t, ts.serialize_cdr(msg, "sensor_msgs/msg/Image"))


def write_mcap(path, frames, pb, compression):
    from mcap.writer import CompressionType
    from mcap_ros2.writer import Writer
    kind = {"zstd": CompressionType.ZSTD, "lz4": CompressionType.LZ4}[compression]
    with open(path, "wb") as f:
        w = Writer(f, compression=kind)
        image = w.register_msgdef("sensor_msgs/msg/Image", IMAGE_DEF)
        info = w.register_msgdef("sensor_msgs/msg/CameraInfo", INFO_DEF)
        for i, img in enumerate(frames):
            t, st = stamp(i)
            header = {"stamp": st, "frame_id": "camera_depth_optical_frame"}
            fields = info_fields(pb)
            fields.update(header=header, binning_x=0, binning_y=0,
                          roi={"x_offset": 0, "y_offset": 0, "height": 0, "width": 0,
                               "do_rectify": False})
            w.write_message(INFO, info, fields, log_time=t, sequence=i)
            w.write_message(DEPTH, image, {
                "header": header, "height": pb.H, "width": pb.W, "encoding": "16UC1",
                "is_bigendian": 0, "step": pb.W * 2,
                "data": np.ascontiguousarray(img, "<u2").tobytes()}, log_time=t, sequence=i)
        w.finish()


def damaged(out, good_mcap, good_db3):
    bad = os.path.join(out, "bad")
    os.makedirs(bad, exist_ok=True)
    data = open(good_mcap, "rb").read()
    open(os.path.join(bad, "cut.mcap"), "wb").write(data[:len(data) // 2])
    # The first chunk's compressed bytes: opcode 0x06 after magic + header record.
    hlen = struct.unpack_from("<Q", data, 9)[0]
    pos = 8 + 9 + hlen
    while data[pos] != 0x06:
        pos += 9 + struct.unpack_from("<Q", data, pos + 1)[0]
    flipped = bytearray(data)
    flipped[pos + 9 + 40 + 200] ^= 0x5A
    open(os.path.join(bad, "flipped.mcap"), "wb").write(bytes(flipped))
    huge = bytearray(data)
    struct.pack_into("<Q", huge, pos + 1, 1 << 62)
    open(os.path.join(bad, "huge_record.mcap"), "wb").write(bytes(huge))
    huge = bytearray(data)
    struct.pack_into("<Q", huge, pos + 9 + 16, 1 << 40)  # uncompressed_size
    open(os.path.join(bad, "huge_chunk.mcap"), "wb").write(bytes(huge))
    open(os.path.join(bad, "notmcap.mcap"), "w").write("not an mcap file\n")
    db = open(good_db3, "rb").read()
    open(os.path.join(bad, "cut.db3"), "wb").write(db[:len(db) // 2])
    open(os.path.join(bad, "garbage.db3"), "wb").write(b"SQLite format 3\0" + bytes(range(256)) * 8)
    huge_image(os.path.join(bad, "huge_image.mcap"))
    other_size(os.path.join(bad, "other_size.mcap"))


def other_size(path):
    """camera_info of 32 x 24 px beside depth images of 16 x 12 px."""
    from mcap.writer import CompressionType
    from mcap_ros2.writer import Writer
    with open(path, "wb") as f:
        w = Writer(f, compression=CompressionType.NONE)
        image = w.register_msgdef("sensor_msgs/msg/Image", IMAGE_DEF)
        info = w.register_msgdef("sensor_msgs/msg/CameraInfo", INFO_DEF)
        header = {"stamp": {"sec": 1, "nanosec": 0}, "frame_id": "d"}
        w.write_message(INFO, info, dict(
            header=header, height=24, width=32, distortion_model="plumb_bob", d=[0.0] * 5,
            k=[20.0, 0, 16, 0, 20.0, 12, 0, 0, 1], r=[1, 0, 0, 0, 1, 0, 0, 0, 1],
            p=[20.0, 0, 16, 0, 0, 20.0, 12, 0, 0, 0, 1, 0], binning_x=0, binning_y=0,
            roi={"x_offset": 0, "y_offset": 0, "height": 0, "width": 0, "do_rectify": False}),
            log_time=1)
        w.write_message(DEPTH, image, {"header": header, "height": 12, "width": 16,
                                       "encoding": "16UC1", "is_bigendian": 0, "step": 32,
                                       "data": bytes(384)}, log_time=1)
        w.finish()


def huge_image(path):
    from mcap.writer import CompressionType, Writer
    with open(path, "wb") as f:
        w = Writer(f, compression=CompressionType.NONE)
        w.start(profile="ros2", library="hostile")
        s = w.register_schema("sensor_msgs/msg/Image", "ros2msg", IMAGE_DEF.encode())
        c = w.register_channel(DEPTH, "cdr", s)
        cdr = (b"\0\1\0\0" + struct.pack("<iI", 0, 0) + struct.pack("<I", 1) + b"\0\0\0\0" +
               struct.pack("<II", 65535, 65535) + struct.pack("<I", 6) + b"16UC1\0" +
               b"\0\0" + struct.pack("<I", 131070) + struct.pack("<I", 8) + b"\0" * 8)
        w.add_message(c, log_time=1, publish_time=1, data=cdr)
        w.finish()


def check_mcap(path, frames):
    """Reads an MCAP file depthbias wrote with the mcap package, decodes every message."""
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory
    counts = {}
    with open(path, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        summary = reader.get_summary()
        for schema, channel, message, ros in reader.iter_decoded_messages():
            counts[channel.topic] = counts.get(channel.topic, 0) + 1
            if channel.topic == DEPTH:
                img = np.frombuffer(bytes(ros.data), "<u2")
                assert ros.encoding == "16UC1", ros.encoding
                assert img.size == ros.width * ros.height and ros.step == 2 * ros.width
                assert (img > 0).any(), "an image without depth"
            elif channel.topic == INFO:
                assert ros.distortion_model in ("plumb_bob", "equidistant")
                assert ros.k[0] > 0 and ros.k[4] > 0
            elif channel.topic == PARAMS:
                names = sorted(p.name for p in ros.new_parameters)
                assert names == ["depth_module.emitter_enabled", "depth_module.visual_preset"]
    compression = sorted({c.compression for c in summary.chunk_indexes})
    print("%s: %s, chunks %s, statistics %d messages" %
          (path, counts, compression, summary.statistics.message_count))
    ok = (counts.get(DEPTH) == frames and counts.get(INFO) == frames and counts.get(PARAMS) == 1
          and compression == ["zstd"])
    return 0 if ok else 1


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("out", nargs="?")
    ap.add_argument("--frames", type=int, default=12)
    ap.add_argument("--check-mcap", nargs=2, metavar=("FILE", "FRAMES"))
    args = ap.parse_args()
    if args.check_mcap:
        return check_mcap(args.check_mcap[0], int(args.check_mcap[1]))
    if not args.out:
        ap.error("OUT_DIR is required")
    out = args.out
    if os.path.exists(out):
        shutil.rmtree(out)
    os.makedirs(out)
    frames, pb = scene_frames(args.frames)
    import rs_record
    cam = rs_record.Camera(pb.W, pb.H, pb.FX, pb.FX, pb.PPX, pb.PPY, 0.001, pb.BASELINE_M)
    rs_record.record(os.path.join(out, "ros1.bag"), lambda i: frames[i], len(frames), cam, 3, 1,
                     False)
    write_rosbags(os.path.join(out, "rosbags_mcap"), frames, pb, "mcap", True)
    write_rosbags(os.path.join(out, "rosbags_sqlite"), frames, pb, "sqlite3", False)
    write_mcap(os.path.join(out, "mcap_zstd.mcap"), frames, pb, "zstd")
    write_mcap(os.path.join(out, "mcap_lz4.mcap"), frames, pb, "lz4")
    db3 = [f for f in os.listdir(os.path.join(out, "rosbags_sqlite")) if f.endswith(".db3")][0]
    damaged(out, os.path.join(out, "mcap_zstd.mcap"), os.path.join(out, "rosbags_sqlite", db3))
    with open(os.path.join(out, "manifest.csv"), "w") as f:
        f.write("bag,distance_m,angle_deg,light,preset,emitter\n")
        for name in ["ros1.bag", "rosbags_mcap", "rosbags_sqlite", "mcap_zstd.mcap",
                     "mcap_lz4.mcap"]:
            f.write("%s,8,20,daylight,HA,on\n" % name)
    print("make_ros2_fixtures: %d frames in 5 recordings and 9 damaged files in %s" %
          (len(frames), out))
    return 0


if __name__ == "__main__":
    sys.exit(main())
