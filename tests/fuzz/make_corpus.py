#!/usr/bin/env python3
"""Writes the checked-in seed corpora (tests/fuzz/corpus/<target>/) from real files, cut to a few lines so the
fuzzers mutate small inputs; binary messages (CDR, CAN frames) are built here field by field; the map and the
vocabulary are made by the project's tools (a tiny vocabulary trained on the KITTI excerpt, maps of the excerpt's
first frames with few features).

  tests/fuzz/make_corpus.py --shared /work/shared/data --sim SIM_SEQUENCE --bin build/release/bin

SIM_SEQUENCE: a folder written by agvslam-sim (objects.txt, odometry.txt, calib.txt, times.txt). Existing seeds are
overwritten; seeds are named after their source.
"""
import argparse
import os
import struct
import subprocess
import tempfile
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))
SRC = os.path.normpath(os.path.join(HERE, "..", ".."))


def head(path, lines):
    with open(path, "rb") as f:
        return b"".join(f.readlines()[:lines])


def put(target, name, data):
    folder = os.path.join(HERE, "corpus", target)
    os.makedirs(folder, exist_ok=True)
    with open(os.path.join(folder, name), "wb") as f:
        f.write(data)


class Cdr:
    """XCDR1 little-endian writer: primitives aligned to their size relative to the end of the 4-byte header."""

    def __init__(self):
        self.body = bytearray()

    def align(self, n):
        while len(self.body) % n:
            self.body.append(0)

    def u8(self, v):
        self.body += struct.pack("<B", v)

    def u32(self, v):
        self.align(4)
        self.body += struct.pack("<I", v)

    def i32(self, v):
        self.align(4)
        self.body += struct.pack("<i", v)

    def u64(self, v):
        self.align(8)
        self.body += struct.pack("<Q", v)

    def f32(self, v):
        self.align(4)
        self.body += struct.pack("<f", v)

    def f64(self, v):
        self.align(8)
        self.body += struct.pack("<d", v)

    def string(self, s):
        b = s.encode() + b"\0"
        self.u32(len(b))
        self.body += b

    def f64s(self, values, counted):
        if counted:
            self.u32(len(values))
        for v in values:
            self.f64(v)

    def message(self):
        return b"\x00\x01\x00\x00" + bytes(self.body)


def header(c, frame_id):
    c.i32(1403715273)
    c.u32(262142976)
    c.string(frame_id)


def pose_with_covariance(c):
    for v in (1.0, 2.0, 0.0, 0.0, 0.0, 0.0, 1.0):
        c.f64(v)
    c.f64s([0.01 * (i % 7 == 0) for i in range(36)], False)


def grey_png(width, height):
    """A small 8-bit grey PNG (a gradient): the excerpts' images are ~400 KB, far too big for a seed."""
    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))
    rows = b"".join(b"\0" + bytes((x * 32 + y * 8) & 0xFF for x in range(width)) for y in range(height))
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 0, 0, 0, 0)) +
            chunk(b"IDAT", zlib.compress(rows)) + chunk(b"IEND", b""))


def cdr_seeds(png):
    # rosbag_cdr: first byte 0 Image, 1 CompressedImage, 2 CameraInfo, 3 Odometry.
    for encoding, channels in (("mono8", 1), ("bgr8", 3), ("mono16", 2)):
        c = Cdr()
        header(c, "camera_left")
        c.u32(2)  # height
        c.u32(4)  # width
        c.string(encoding)
        c.u8(0)
        c.u32(4 * channels)
        c.u32(8 * channels)
        c.body += bytes(range(8 * channels))
        put("rosbag_cdr", "image_" + encoding, b"\x00" + c.message())
    c = Cdr()
    header(c, "camera_left")
    c.string("png")
    c.u32(len(png))
    c.body += png
    put("rosbag_cdr", "compressed_png", b"\x01" + c.message())
    c = Cdr()
    header(c, "camera_left")
    c.u32(376)
    c.u32(1241)
    c.string("plumb_bob")
    c.f64s([0.0] * 5, True)
    c.f64s([718.856, 0, 607.1928, 0, 718.856, 185.2157, 0, 0, 1], False)
    c.f64s([1, 0, 0, 0, 1, 0, 0, 0, 1], False)
    c.f64s([718.856, 0, 607.1928, -386.1448, 0, 718.856, 185.2157, 0, 0, 0, 1, 0], False)
    put("rosbag_cdr", "camera_info", b"\x02" + c.message())
    c = Cdr()
    header(c, "odom")
    c.string("base_link")
    pose_with_covariance(c)
    for v in (0.5, 0, 0, 0, 0, 0.1):
        c.f64(v)
    c.f64s([0.0] * 36, False)
    put("rosbag_cdr", "odometry", b"\x03" + c.message())

    # dds_samples: first byte 0 pose, 1 odom, 2 status; then the encapsulation identifier and options.
    c = Cdr()
    header(c, "map")
    pose_with_covariance(c)
    put("dds_samples", "pose", b"\x00" + c.message())
    c = Cdr()
    header(c, "map")
    c.string("base_link")
    pose_with_covariance(c)
    for v in (0.5, 0, 0, 0, 0, 0.1):
        c.f64(v)
    c.f64s([0.0] * 36, False)
    put("dds_samples", "odom", b"\x01" + c.message())
    c = Cdr()
    header(c, "map")
    c.u8(1)
    c.u64(120)
    c.u64(118)
    c.u64(2)
    for v in (20.0, 0.05, 35.0):
        c.f32(v)
    c.u8(1)
    for v in (1.01, 0.02, 0.5):
        c.f32(v)
    put("dds_samples", "status", b"\x02" + c.message())


def crc8_sae_j1850(data):
    crc = 0xFF
    for b in data:
        crc ^= b
        for _ in range(8):
            crc = ((crc << 1) ^ 0x1D) & 0xFF if crc & 0x80 else (crc << 1) & 0xFF
    return crc ^ 0xFF


def can_seeds():
    # can_frames: [flags, len, payload] per frame; VEHICLE_ODOMETRY at 0x306: Speed int16 mm/s, YawRate int16
    # 0.01 deg/s, Counter bits 52..55, Crc last byte (pose_frames.h).
    frames = b""
    for counter, (speed, yaw) in enumerate(((500, 0), (520, 150), (-300, -2000))):
        payload = bytearray(struct.pack("<hh", speed, yaw)) + bytearray(4)
        payload[6] = (counter & 0xF) << 4
        payload[7] = crc8_sae_j1850(struct.pack("<I", 0x306) + bytes(payload[:7]))
        frames += bytes([0, 8]) + bytes(payload)
    put("can_frames", "vehicle_odometry", frames)
    put("can_frames", "short_frame", bytes([0, 3, 1, 2, 3]))
    put("candump", "frames.log",
        b"(1699999999.123456) vcan0 300#0102030405060708\n"
        b"(1699999999.223456) vcan0 12345678#0102\n"
        b"(1699999999.323456) vcan0 308##1" + b"00" * 48 + b"\n"
        b"(1699999999.423456) vcan0 123#R\n"
        b"(1699999999.523456) vcan0 20000004#0000000000000000\n"
        b"# comment\n\n")


def tool_seeds(shared, bin_dir):
    kitti = os.path.join(shared, "kitti01_f000-050")
    with tempfile.TemporaryDirectory() as tmp:
        vocab = os.path.join(tmp, "k3l2.bin")
        subprocess.run([os.path.join(bin_dir, "agvslam-vocab"), "--images", os.path.join(kitti, "image_l"), "--k", "3",
                        "--levels", "2", "--max-features-per-image", "40", "--frame-step", "10", "--out", vocab,
                        "--description", "fuzz seed"], check=True, capture_output=True)
        put("vocabulary", "k3l2.bin", open(vocab, "rb").read())
        with open(os.path.join(tmp, "place.yaml"), "w") as f:
            f.write("vocabulary:\n  file: k3l2.bin\n  direct_index_level: 1\n")
        # Few features so the maps stay small; the tracker's start thresholds lowered to match.
        for name, features, frames in (("one_keyframe.map", 120, "0:3"), ("keyframes.map", 300, "0:4")):
            with open(os.path.join(tmp, "features.yaml"), "w") as f:
                f.write("orb:\n  n_features: %d\n" % features)
            with open(os.path.join(tmp, "slam.yaml"), "w") as f:
                f.write("tracking:\n  min_init_features: %d\n  min_init_stereo: %d\n" % (features // 2, features // 4))
            out = os.path.join(tmp, name)
            subprocess.run([os.path.join(bin_dir, "agvslam-run"), "--dataset", kitti, "--out",
                            os.path.join(tmp, "traj.txt"), "--frames", frames, "--dynamic", "off", "--mapping",
                            "inline", "--loop", "off", "--params-features", os.path.join(tmp, "features.yaml"),
                            "--params-slam", os.path.join(tmp, "slam.yaml"), "--params-place",
                            os.path.join(tmp, "place.yaml"), "--save-map", out], check=True, capture_output=True)
            put("map", name, open(out, "rb").read())


def rosbag_metadata(storage="sqlite3", compression='""', files=("bag_0.db3",), topics=(
        ("/camera/left/image_raw", "sensor_msgs/msg/Image", 50), ("/camera/right/image_raw", "sensor_msgs/msg/Image", 50),
        ("/odom", "nav_msgs/msg/Odometry", 250))):
    # metadata.yaml as ros2 bag record (rosbag2 version 5, Humble) writes it.
    s = ("rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: %s\n  duration:\n"
         "    nanoseconds: 2450000000\n  starting_time:\n    nanoseconds_since_epoch: 1700000000000000000\n"
         "  message_count: 350\n  topics_with_message_count:\n" % storage)
    for name, kind, count in topics:
        s += ("    - topic_metadata:\n        name: %s\n        type: %s\n        serialization_format: cdr\n"
              "        offered_qos_profiles: \"\"\n      message_count: %d\n" % (name, kind, count))
    s += '  compression_format: %s\n  compression_mode: ""\n  relative_file_paths:\n' % compression
    s += "".join("    - %s\n" % f for f in files)
    s += ("  files:\n    - path: %s\n      starting_time:\n        nanoseconds_since_epoch: 1700000000000000000\n"
          "      duration:\n        nanoseconds: 2450000000\n      message_count: 350\n" % files[0])
    return s.encode()


def rosbag_metadata_seeds():
    put("rosbag_metadata", "humble_stereo_odom.yaml", rosbag_metadata())
    put("rosbag_metadata", "mcap.yaml", rosbag_metadata(storage="mcap", files=("bag_0.mcap",)))
    put("rosbag_metadata", "zstd.yaml", rosbag_metadata(compression="zstd"))
    put("rosbag_metadata", "two_files.yaml", rosbag_metadata(files=("bag_0.db3", "bag_1.db3")))
    put("rosbag_metadata", "compressed_images.yaml", rosbag_metadata(topics=tuple(
        (t, k, 40) for t, k in (("/stereo/left/image_raw/compressed", "sensor_msgs/msg/CompressedImage"),
                                ("/stereo/right/image_raw/compressed", "sensor_msgs/msg/CompressedImage"),
                                ("/stereo/left/camera_info", "sensor_msgs/msg/CameraInfo"),
                                ("/stereo/right/camera_info", "sensor_msgs/msg/CameraInfo")))))
    put("rosbag_metadata", "query.txt", b"left=/camera/left/image_raw&right=/camera/right/image_raw&odom=/odom")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--shared", required=True, help="the shared data folder (kitti01_f000-050, euroc_v101_f000-094)")
    ap.add_argument("--sim", required=True, help="a simulator sequence folder")
    ap.add_argument("--bin", required=True, help="the release build's bin folder (agvslam-run, agvslam-vocab)")
    a = ap.parse_args()
    kitti = os.path.join(a.shared, "kitti01_f000-050")
    euroc = os.path.join(a.shared, "euroc_v101_f000-094", "mav0")

    put("calibration", "kitti_calib.txt", open(os.path.join(kitti, "calib.txt"), "rb").read())
    put("calibration", "sim_calib.txt", open(os.path.join(a.sim, "calib.txt"), "rb").read())
    put("calibration", "agvslamd_calibration_example.yaml",
        open(os.path.join(SRC, "params", "agvslamd_calibration_example.yaml"), "rb").read())
    put("calibration", "orbslam.yaml",
        b"%YAML:1.0\nCamera.fx: 435.2\nCamera.fy: 435.2\nCamera.cx: 367.4\nCamera.cy: 252.2\nCamera.bf: 47.9\n"
        b"Camera.width: 752\nCamera.height: 480\n")
    put("calibration", "kalibr_camchain.yaml",
        b"cam0:\n  camera_model: pinhole\n  intrinsics: [458.654, 457.296, 367.215, 248.375]\n"
        b"  distortion_model: radtan\n  distortion_coeffs: [-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05]\n"
        b"  resolution: [752, 480]\ncam1:\n  camera_model: pinhole\n  intrinsics: [457.587, 456.134, 379.999, 255.238]\n"
        b"  distortion_model: radtan\n  distortion_coeffs: [-0.28368365, 0.07451284, -0.00010473, -3.555907e-05]\n"
        b"  resolution: [752, 480]\n  T_cn_cnm1:\n  - [0.99999, 0.00231, 0.00037, -0.11007]\n"
        b"  - [-0.00231, 0.99996, 0.00858, 0.00040]\n  - [-0.00035, -0.00858, 0.99996, -0.00085]\n"
        b"  - [0.0, 0.0, 0.0, 1.0]\n")
    for cam in ("cam0", "cam1"):
        put("euroc_sensor", cam + "_sensor.yaml", open(os.path.join(euroc, cam, "sensor.yaml"), "rb").read())
    put("euroc_csv", "cam0_data.csv", head(os.path.join(euroc, "cam0", "data.csv"), 7))
    put("euroc_csv", "groundtruth.csv",
        b"#timestamp,p_RS_R_x [m],p_RS_R_y [m],p_RS_R_z [m],q_RS_w [],q_RS_x [],q_RS_y [],q_RS_z []\n"
        b"1403715273262142976,0.878612,2.142470,0.947262,0.060514,-0.828459,-0.058956,-0.553641\n"
        b"1403715273312143104,0.879107,2.142052,0.947328,0.060469,-0.828398,-0.058774,-0.553768\n")
    put("kitti_times", "kitti_times.txt", head(os.path.join(kitti, "times.txt"), 8))
    put("kitti_times", "sim_times.txt", head(os.path.join(a.sim, "times.txt"), 8))
    put("trajectory", "kitti_poses.txt", head(os.path.join(kitti, "poses.txt"), 4))
    put("trajectory", "tum.txt",
        head(os.path.join(a.shared, "euroc_v101_f000-094", "gt_orbslam3_left_cam", "V101_GT.txt"), 4))
    put("trajectory", "euroc.csv", b"#timestamp [ns],x,y,z,qw,qx,qy,qz\n"
        b"1403715273262142976,0.878612,2.142470,0.947262,0.060514,-0.828459,-0.058956,-0.553641\n")
    put("odometry_csv", "odometry.csv", b"# t_s, speed_mps, yaw_rate_radps\n0.00,0.50,0.000\n0.05,0.52,0.010\n"
        b"0.10,0.55,-0.020\n")
    put("odometry_csv", "sim_odometry_tum.txt", head(os.path.join(a.sim, "odometry.txt"), 4))
    put("objects", "objects.txt", head(os.path.join(a.sim, "objects.txt"), 6))
    for name in ("place.yaml", "agvslamd.yaml", "agvslamd_dataset.yaml"):
        put("params", name, open(os.path.join(SRC, "params", name), "rb").read())
    put("dbc", "agvslam.dbc", open(os.path.join(SRC, "deploy", "agvslam.dbc"), "rb").read())
    cdr_seeds(grey_png(8, 4))
    can_seeds()
    rosbag_metadata_seeds()
    tool_seeds(a.shared, a.bin)


if __name__ == "__main__":
    main()
