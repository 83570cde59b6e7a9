#!/usr/bin/python3
"""Writes a EuRoC ASL folder's cam0 images (and optionally its IMU, a compressed copy, a
rectified copy and camera_info) into a rosbag.

    scripts/make_bag.sh ASL_FOLDER OUT.bag [--topic /cam0/image_raw] [--frame-id cam0]
                        [--camera cam0] [--max-frames N]
                        [--imu] [--imu-topic /imu0] [--imu-frame-id imu0] [--imu-rate 200]
                        [--imu-noise] [--seed N]
                        [--compressed jpeg|png] [--jpeg-quality 95] [--no-raw]
                        [--camera-info] [--rectified]

ASL_FOLDER is a sequence folder (containing mav0/) or its mav0/ folder. Each row
of <camera>/data.csv ("timestamp [ns], filename") becomes one sensor_msgs/Image
(mono8; colour or 16-bit images are converted) stamped with the row's exact
nanoseconds, written at that time.

--imu writes sensor_msgs/Imu on --imu-topic: mav0/imu0/data.csv when the folder has
one (a real EuRoC sequence), else synthesized from the body ground truth
(mav0/state_groundtruth_estimate0/data.csv, the body = IMU frame, world z up, as
EuRoC and the renders write it): at --imu-rate over the images' span, specific force
f_b = R_w_b^T (a_w - g_w) with g_w = (0, 0, -9.81) and angular rate w_b from the
differentiated orientation. Position and orientation are smoothed by a local cubic
fit over +-max(0.1 s, 3 samples) of ground truth (EuRoC's 200 Hz ground truth is too
noisy to differentiate twice as it is). --imu-noise adds EuRoC's white noise
(accelerometer 2.0e-3 m/s^2/sqrt(Hz), gyroscope 1.6968e-4 rad/s/sqrt(Hz)) and a
constant random bias (0.05 m/s^2, 0.005 rad/s per axis, 1 sigma).

--compressed writes sensor_msgs/CompressedImage on <topic>/compressed as
compressed_image_transport does ("mono8; jpeg compressed mono8"); --no-raw leaves the
raw images out. --camera-info writes sensor_msgs/CameraInfo on <ns>/camera_info (K, D
from cam0/sensor.yaml, plumb_bob; P the rectified camera: K's focal lengths, principal
point at the image centre, so P != K), each written 1 ms before its
image (same header stamp) so that the first image finds a calibration; --rectified also writes the
rectified image on <ns>/image_rect (OpenCV remap to P). A python3 script run by /usr/bin/python3 (Debian's rosbag module; the pyenv
python on PATH lacks it).
"""
import argparse
import csv
import math
import os
import re
import sys

import cv2
import numpy as np
import rosbag
import rospy
from sensor_msgs.msg import CameraInfo, CompressedImage, Image, Imu

GRAVITY = 9.81


def find_mav0(asl):
    for base in (os.path.join(asl, "mav0"), asl):
        if os.path.isdir(base):
            return base
    sys.exit("make_bag.sh: no folder %s" % asl)


def find_camera_dir(asl, camera):
    for base in (os.path.join(asl, "mav0"), asl):
        d = os.path.join(base, camera)
        if os.path.isfile(os.path.join(d, "data.csv")):
            return d
    sys.exit("make_bag.sh: no %s/data.csv under %s (nor %s/mav0)" % (camera, asl, asl))


def read_rows(csv_path):
    rows = []
    with open(csv_path, newline="") as f:
        for line_no, row in enumerate(csv.reader(f), 1):
            if not row or row[0].lstrip().startswith("#"):
                continue
            if len(row) < 2 or not row[0].strip().isdigit():
                sys.exit("make_bag.sh: %s:%d: expected 'timestamp_ns,filename'" % (csv_path, line_no))
            rows.append((int(row[0].strip()), row[1].strip()))
    return rows


def read_numeric_csv(path, min_cols):
    rows = []
    with open(path, newline="") as f:
        for line_no, row in enumerate(csv.reader(f), 1):
            if not row or row[0].lstrip().startswith("#"):
                continue
            if len(row) < min_cols:
                sys.exit("make_bag.sh: %s:%d: expected at least %d columns" % (path, line_no, min_cols))
            try:
                rows.append([int(row[0])] + [float(v) for v in row[1:min_cols]])
            except ValueError:
                sys.exit("make_bag.sh: %s:%d: not a number" % (path, line_no))
    if not rows:
        sys.exit("make_bag.sh: %s has no rows" % path)
    return rows


def to_mono8(image):
    if image.ndim == 3:
        code = cv2.COLOR_BGRA2GRAY if image.shape[2] == 4 else cv2.COLOR_BGR2GRAY
        image = cv2.cvtColor(image, code)
    if image.dtype != "uint8":
        image = (image >> 8).astype("uint8")
    return image


def stamp_of(ns):
    return rospy.Time(ns // 1000000000, ns % 1000000000)


# ---------------------------------------------------------------- calibration (camera_info)
def read_sensor_yaml(path):
    """The few keys of an EuRoC sensor.yaml needed here (OpenCV's %YAML:1.0 is not PyYAML's)."""
    text = open(path).read()

    def numbers(key):
        m = re.search(r"^\s*%s\s*:\s*\[([^\]]*)\]" % key, text, re.M)
        if not m:
            sys.exit("make_bag.sh: %s has no '%s: [...]'" % (path, key))
        return [float(v) for v in m.group(1).replace("\n", " ").split(",") if v.strip()]

    intr = numbers("intrinsics")
    res = numbers("resolution")
    dist = numbers("distortion_coefficients")
    model = re.search(r"^\s*distortion_model\s*:\s*(\S+)", text, re.M)
    if model and model.group(1) not in ("radial-tangential", "radtan", "plumb_bob"):
        sys.exit("make_bag.sh: --camera-info supports radial-tangential only (%s)" % model.group(1))
    K = np.array([[intr[0], 0, intr[2]], [0, intr[1], intr[3]], [0, 0, 1]], dtype=np.float64)
    D = np.array((dist + [0.0] * 5)[:5], dtype=np.float64)
    return K, D, int(res[0]), int(res[1])


def camera_info_msg(K, D, P, w, h, frame_id, stamp):
    info = CameraInfo()
    info.header.stamp = stamp
    info.header.frame_id = frame_id
    info.width, info.height = w, h
    info.distortion_model = "plumb_bob"
    info.D = [float(v) for v in D]
    info.K = [float(v) for v in K.ravel()]
    info.R = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]
    info.P = [float(P[0, 0]), 0.0, float(P[0, 2]), 0.0, 0.0, float(P[1, 1]), float(P[1, 2]), 0.0, 0.0, 0.0, 1.0, 0.0]
    return info


# ---------------------------------------------------------------- IMU
def quat_to_rot(q):
    """q = (w, x, y, z) unit quaternions, shape (N, 4) -> (N, 3, 3)."""
    w, x, y, z = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
    return np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
        np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
        np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1)], -2)


def rot_log(R):
    """(N, 3, 3) rotations -> (N, 3) rotation vectors."""
    tr = np.clip((np.trace(R, axis1=1, axis2=2) - 1) / 2, -1.0, 1.0)
    a = np.arccos(tr)
    v = np.stack([R[:, 2, 1] - R[:, 1, 2], R[:, 0, 2] - R[:, 2, 0], R[:, 1, 0] - R[:, 0, 1]], -1)
    s = np.where(a > 1e-9, a / (2 * np.sin(np.maximum(a, 1e-12))), 0.5)
    return v * s[:, None]


def local_cubic(t_gt, values, t_out, half_window):
    """Least-squares cubic around each output time: value and first and second derivatives."""
    out = np.zeros((len(t_out), 3, values.shape[1]))
    for i, t in enumerate(t_out):
        lo, hi = np.searchsorted(t_gt, [t - half_window, t + half_window])
        lo, hi = max(0, lo - 1), min(len(t_gt), hi + 1)
        if hi - lo < 5:
            lo, hi = max(0, min(lo, len(t_gt) - 5)), min(len(t_gt), max(hi, 5))
        dt = t_gt[lo:hi] - t
        A = np.stack([np.ones_like(dt), dt, dt * dt, dt * dt * dt], -1)
        c, *_ = np.linalg.lstsq(A, values[lo:hi], rcond=None)
        out[i, 0], out[i, 1], out[i, 2] = c[0], c[1], 2 * c[2]
    return out


def synthesize_imu(gt_rows, t_start, t_end, rate, noise, seed):
    gt = np.array(gt_rows, dtype=np.float64)
    t_ns = np.array([r[0] for r in gt_rows], dtype=np.int64)
    t_gt = (t_ns - t_ns[0]) * 1e-9
    p = gt[:, 1:4]
    q = gt[:, 4:8]
    q = q / np.linalg.norm(q, axis=1, keepdims=True)
    for k in range(1, len(q)):  # one hemisphere, so the fit of q is smooth
        if np.dot(q[k], q[k - 1]) < 0:
            q[k] = -q[k]
    gt_rate = (len(t_gt) - 1) / max(t_gt[-1] - t_gt[0], 1e-9)
    half = max(0.1, 3.0 / gt_rate)
    period_ns = int(round(1e9 / rate))
    first = max(t_start, t_ns[0])
    last = min(t_end, t_ns[-1])
    out_ns = np.arange(first, last + 1, period_ns, dtype=np.int64)
    t_out = (out_ns - t_ns[0]) * 1e-9
    pos = local_cubic(t_gt, p, t_out, half)
    a_w = pos[:, 2]
    quat = local_cubic(t_gt, q, t_out, half)
    qn = quat[:, 0] / np.linalg.norm(quat[:, 0], axis=1, keepdims=True)
    R_w_b = quat_to_rot(qn)
    # Angular rate in the body: from R(t - h)^T R(t + h) over a small h, the rotation of the
    # fitted quaternion curve (q(t) + q'(t) dt, normalized).
    h = 0.5 / rate
    qa = quat[:, 0] - h * quat[:, 1]
    qb = quat[:, 0] + h * quat[:, 1]
    Ra = quat_to_rot(qa / np.linalg.norm(qa, axis=1, keepdims=True))
    Rb = quat_to_rot(qb / np.linalg.norm(qb, axis=1, keepdims=True))
    omega = rot_log(np.einsum("nji,njk->nik", Ra, Rb)) / (2 * h)
    g_w = np.array([0.0, 0.0, -GRAVITY])
    f_b = np.einsum("nji,nj->ni", R_w_b, a_w - g_w)
    if noise:
        rng = np.random.default_rng(seed)
        f_b += rng.normal(0.0, 2.0e-3 * math.sqrt(rate), f_b.shape) + rng.normal(0.0, 0.05, 3)
        omega += rng.normal(0.0, 1.6968e-4 * math.sqrt(rate), omega.shape) + rng.normal(0.0, 0.005, 3)
    return out_ns, omega, f_b


def imu_samples(mav0, t_start, t_end, rate, noise, seed):
    real = os.path.join(mav0, "imu0", "data.csv")
    if os.path.isfile(real):
        rows = read_numeric_csv(real, 7)
        rows = [r for r in rows if t_start <= r[0] <= t_end]
        ns = np.array([r[0] for r in rows], dtype=np.int64)
        data = np.array([r[1:7] for r in rows])
        return ns, data[:, 0:3], data[:, 3:6], "mav0/imu0/data.csv"
    gt = os.path.join(mav0, "state_groundtruth_estimate0", "data.csv")
    if not os.path.isfile(gt):
        sys.exit("make_bag.sh: --imu needs mav0/imu0/data.csv or mav0/state_groundtruth_estimate0/data.csv")
    rows = read_numeric_csv(gt, 8)
    if len(rows) < 5:
        sys.exit("make_bag.sh: %s: too few ground-truth poses for --imu" % gt)
    ns, omega, f = synthesize_imu(rows, t_start, t_end, rate, noise, seed)
    return ns, omega, f, "synthesized from %s at %g Hz%s" % (os.path.relpath(gt, mav0), rate,
                                                            " with EuRoC noise" if noise else "")


def imu_msg(ns, omega, f, frame_id, seq):
    m = Imu()
    m.header.seq = seq
    m.header.stamp = stamp_of(int(ns))
    m.header.frame_id = frame_id
    m.orientation_covariance[0] = -1.0  # no orientation
    m.angular_velocity.x, m.angular_velocity.y, m.angular_velocity.z = (float(v) for v in omega)
    m.linear_acceleration.x, m.linear_acceleration.y, m.linear_acceleration.z = (float(v) for v in f)
    return m


def main():
    parser = argparse.ArgumentParser(description="EuRoC ASL cam0 images (+ IMU) -> rosbag")
    parser.add_argument("asl_folder")
    parser.add_argument("out_bag")
    parser.add_argument("--topic", default="/cam0/image_raw")
    parser.add_argument("--frame-id", default="cam0")
    parser.add_argument("--camera", default="cam0")
    parser.add_argument("--max-frames", type=int, default=0, help="0: all")
    parser.add_argument("--imu", action="store_true")
    parser.add_argument("--imu-topic", default="/imu0")
    parser.add_argument("--imu-frame-id", default="imu0")
    parser.add_argument("--imu-rate", type=float, default=200.0)
    parser.add_argument("--imu-noise", action="store_true")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--compressed", choices=["jpeg", "png"], default=None)
    parser.add_argument("--jpeg-quality", type=int, default=95)
    parser.add_argument("--no-raw", action="store_true")
    parser.add_argument("--camera-info", action="store_true")
    parser.add_argument("--rectified", action="store_true")
    args = parser.parse_args()
    if args.no_raw and not args.compressed:
        sys.exit("make_bag.sh: --no-raw without --compressed leaves no image")
    if not (args.imu_rate > 0):
        sys.exit("make_bag.sh: --imu-rate must be > 0")

    cam_dir = find_camera_dir(args.asl_folder, args.camera)
    rows = read_rows(os.path.join(cam_dir, "data.csv"))
    if args.max_frames > 0:
        rows = rows[:args.max_frames]
    if not rows:
        sys.exit("make_bag.sh: no images listed in %s/data.csv" % cam_dir)
    ns_topic = args.topic.rsplit("/", 1)[0] if "/" in args.topic.strip("/") else ""
    maps = None
    if args.camera_info or args.rectified:
        K, D, w, h = read_sensor_yaml(os.path.join(cam_dir, "sensor.yaml"))
        # The rectified camera: K's focal lengths, the principal point at the image centre (P != K).
        # Keeping the focal length keeps the resolution at the centre; getOptimalNewCameraMatrix
        # (alpha 0) shrank it to 178 px/rad from 229 on the test camera and the ATE grew by 30 %.
        P = np.array([[K[0, 0], 0.0, (w - 1) / 2.0], [0.0, K[1, 1], (h - 1) / 2.0], [0.0, 0.0, 1.0]])
        if args.rectified:
            maps = cv2.initUndistortRectifyMap(K, D, None, P, (w, h), cv2.CV_32FC1)

    imu = None
    if args.imu:
        imu = imu_samples(find_mav0(args.asl_folder), rows[0][0], rows[-1][0], args.imu_rate, args.imu_noise,
                          args.seed)
    written = 0
    with rosbag.Bag(args.out_bag, "w") as bag:
        if imu is not None:
            for seq, (ns, omega, f) in enumerate(zip(imu[0], imu[1], imu[2])):
                bag.write(args.imu_topic, imu_msg(ns, omega, f, args.imu_frame_id, seq), t=stamp_of(int(ns)))
        for seq, (ns, name) in enumerate(rows):
            path = os.path.join(cam_dir, "data", name)
            image = cv2.imread(path, cv2.IMREAD_UNCHANGED)
            if image is None:
                sys.exit("make_bag.sh: cannot read image %s" % path)
            image = to_mono8(image)
            stamp = stamp_of(ns)
            msg = Image()
            msg.header.seq = seq
            msg.header.stamp = stamp
            msg.header.frame_id = args.frame_id
            msg.height, msg.width = image.shape[:2]
            msg.encoding = "mono8"
            msg.is_bigendian = 0
            msg.step = msg.width
            msg.data = image.tobytes()
            if not args.no_raw:
                bag.write(args.topic, msg, t=stamp)
            if args.compressed:
                c = CompressedImage()
                c.header = msg.header
                if args.compressed == "jpeg":
                    ok, buf = cv2.imencode(".jpg", image, [cv2.IMWRITE_JPEG_QUALITY, args.jpeg_quality])
                    c.format = "mono8; jpeg compressed mono8"
                else:
                    ok, buf = cv2.imencode(".png", image)
                    c.format = "mono8; png compressed mono8"
                if not ok:
                    sys.exit("make_bag.sh: cannot encode %s" % path)
                c.data = buf.tobytes()
                bag.write(args.topic + "/compressed", c, t=stamp)
            if args.camera_info:
                # Played 1 ms before its image, so that a subscriber has the calibration for the first image.
                bag.write(ns_topic + "/camera_info", camera_info_msg(K, D, P, w, h, args.frame_id, stamp),
                          t=stamp_of(max(0, ns - 1000000)))
            if maps is not None:
                rect = cv2.remap(image, maps[0], maps[1], cv2.INTER_LINEAR)
                r = Image()
                r.header = msg.header
                r.height, r.width = rect.shape[:2]
                r.encoding = "mono8"
                r.step = r.width
                r.data = rect.tobytes()
                bag.write(ns_topic + "/image_rect", r, t=stamp)
            written += 1
    extra = []
    if imu is not None:
        extra.append("%d IMU samples on %s (%s)" % (len(imu[0]), args.imu_topic, imu[3]))
    if args.compressed:
        extra.append("%s on %s/compressed" % (args.compressed, args.topic))
    if args.camera_info:
        extra.append("camera_info on %s/camera_info" % ns_topic)
    if maps is not None:
        extra.append("rectified images on %s/image_rect" % ns_topic)
    print("make_bag.sh: %d images from %s -> %s (%s%s)%s" % (
        written, cam_dir, args.out_bag, "no raw images, " if args.no_raw else "", args.topic,
        "".join("; " + e for e in extra)))


if __name__ == "__main__":
    main()
