#!/usr/bin/python3
"""Makes the rostests' input: a short monocular sequence of a textured room with
exact ground truth, as a rosbag.

    make_test_bag.py OUT_DIR [--frames N] [--long-frames N] [--generator PATH] [--make-bag PATH]

Writes OUT_DIR/sequence.bag (/cam0/image_raw, mono8, frame_id cam0),
OUT_DIR/calibration.yaml (EuRoC sensor.yaml format) and OUT_DIR/groundtruth.tum
(T_w_c of every frame). With --generator (the project's vitamin_e_make_sequence)
the sequence comes from it and --make-bag (scripts/make_bag.sh) bags it;
otherwise the room is ray-cast here with numpy.

With the generator, also OUT_DIR/sensors.bag: the same images with everything the
ROS-interface tests need: /imu0 synthesized by make_bag.sh --imu,
/cam0/image_raw/compressed (jpeg), /cam0/camera_info and /cam0/image_rect. The
generator's body is its camera; here the sequence gets EuRoC's body instead (its
cam0 T_BS, x up), written as the body ground truth and the calibration's T_BS, so
the camera -> IMU rotation is exercised as on EuRoC. OUT_DIR/calibration_camera_body.yaml
is the generator's own calibration (T_BS identity): a wrong one for sensors.bag's IMU.

--long-frames N: also OUT_DIR/long.bag and long_calibration.yaml, a sequence of N
frames (the mesh stream's test: the camera goes on around the room).
"""
import argparse
import glob
import math
import os
import shutil
import subprocess
import sys

import numpy as np

WIDTH, HEIGHT = 376, 240
FX = FY = 230.0
CX, CY = 187.5, 119.5
ROOM_LO = np.array([-3.0, -2.0, -2.0])
ROOM_HI = np.array([3.0, 1.5, 4.0])
T0_NS = 1000 * 10**9
PERIOD_NS = 50 * 10**6


def rot_y(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def pose(i, n):
    """Camera (optical: z forward, y down) in the world: a sideways arc looking at the far wall."""
    s = i / max(1, n - 1)
    t = np.array([-0.6 + 1.2 * s, 0.1 * math.sin(2 * math.pi * s), 0.3 * s])
    return rot_y(0.15 * math.sin(math.pi * s) - 0.05), t


def texture(face, a, b, rng_seed=7):
    """Multi-octave value noise on the face's 2D coordinates (a, b) in metres, plus dark dots."""
    out = np.zeros_like(a)
    amp_total = 0.0
    for octave, (cell, amp) in enumerate([(0.6, 1.0), (0.2, 0.6), (0.07, 0.35)]):
        rng = np.random.default_rng(rng_seed + 31 * face + octave)
        grid = rng.random((256, 256))
        x = a / cell + 128.0
        y = b / cell + 128.0
        x0 = np.clip(np.floor(x).astype(int), 0, 254)
        y0 = np.clip(np.floor(y).astype(int), 0, 254)
        fx = np.clip(x - x0, 0, 1)
        fy = np.clip(y - y0, 0, 1)
        fx = fx * fx * (3 - 2 * fx)
        fy = fy * fy * (3 - 2 * fy)
        v = (grid[y0, x0] * (1 - fx) * (1 - fy) + grid[y0, x0 + 1] * fx * (1 - fy) +
             grid[y0 + 1, x0] * (1 - fx) * fy + grid[y0 + 1, x0 + 1] * fx * fy)
        out += amp * v
        amp_total += amp
    return out / amp_total


def render(R_w_c, t_w_c):
    u, v = np.meshgrid(np.arange(WIDTH, dtype=float), np.arange(HEIGHT, dtype=float))
    rays_c = np.stack([(u - CX) / FX, (v - CY) / FY, np.ones_like(u)], axis=-1)
    d = rays_c @ R_w_c.T
    with np.errstate(divide="ignore", invalid="ignore"):
        bound = np.where(d > 0, ROOM_HI, ROOM_LO)
        t_axis = np.where(np.abs(d) > 1e-12, (bound - t_w_c) / d, np.inf)
    axis = np.argmin(t_axis, axis=-1)
    t = np.take_along_axis(t_axis, axis[..., None], axis=-1)[..., 0]
    p = t_w_c + d * t[..., None]
    face = axis * 2 + (np.take_along_axis(d, axis[..., None], axis=-1)[..., 0] > 0)
    img = np.zeros_like(t)
    for f in range(6):
        m = face == f
        if not m.any():
            continue
        other = [k for k in range(3) if k != f // 2]
        img[m] = texture(f, p[m][:, other[0]], p[m][:, other[1]])
    img = (img - img.min()) / max(1e-9, img.max() - img.min())
    return np.clip(30 + 200 * img, 0, 255).astype(np.uint8)


def quat(R):
    w = math.sqrt(max(0.0, 1 + R[0, 0] + R[1, 1] + R[2, 2])) / 2
    x = math.copysign(math.sqrt(max(0.0, 1 + R[0, 0] - R[1, 1] - R[2, 2])) / 2, R[2, 1] - R[1, 2])
    y = math.copysign(math.sqrt(max(0.0, 1 - R[0, 0] + R[1, 1] - R[2, 2])) / 2, R[0, 2] - R[2, 0])
    z = math.copysign(math.sqrt(max(0.0, 1 - R[0, 0] - R[1, 1] + R[2, 2])) / 2, R[1, 0] - R[0, 1])
    return x, y, z, w


def draw(out_dir, frames):
    import rosbag
    import rospy
    from sensor_msgs.msg import Image
    with rosbag.Bag(os.path.join(out_dir, "sequence.bag"), "w") as bag, \
            open(os.path.join(out_dir, "groundtruth.tum"), "w") as gt:
        for i in range(frames):
            R, t = pose(i, frames)
            ns = T0_NS + i * PERIOD_NS
            stamp = rospy.Time(ns // 10**9, ns % 10**9)
            img = render(R, t)
            msg = Image()
            msg.header.seq = i
            msg.header.stamp = stamp
            msg.header.frame_id = "cam0"
            msg.height, msg.width = img.shape
            msg.encoding = "mono8"
            msg.step = msg.width
            msg.data = img.tobytes()
            bag.write("/cam0/image_raw", msg, t=stamp)
            gt.write("%d.%09d %.9f %.9f %.9f %.9f %.9f %.9f %.9f\n" % ((ns // 10**9, ns % 10**9) + tuple(t) + quat(R)))
    with open(os.path.join(out_dir, "calibration.yaml"), "w") as f:
        f.write("%%YAML:1.0\nsensor_type: camera\ncomment: rostest room\n"
                "T_BS:\n  cols: 4\n  rows: 4\n  data: [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0]\n"
                "rate_hz: 20\nresolution: [%d, %d]\ncamera_model: pinhole\nintrinsics: [%g, %g, %g, %g]\n"
                "distortion_model: radial-tangential\ndistortion_coefficients: [0.0, 0.0, 0.0, 0.0]\n"
                % (WIDTH, HEIGHT, FX, FY, CX, CY))


# EuRoC cam0's T_BS (camera in body; the body = IMU frame has x up).
T_BS_EUROC = np.array([[0.0148655429818, -0.999880929698, 0.00414029679422, -0.0216401454975],
                       [0.999557249008, 0.0149672133247, 0.025715529948, -0.064676986768],
                       [-0.0257744366974, 0.00375618835797, 0.999660727178, 0.00981073058949],
                       [0.0, 0.0, 0.0, 1.0]])


def rot_of_quat(x, y, z, w):
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def use_euroc_body(seq):
    """Re-expresses the body ground truth with EuRoC's T_BS: T_w_b = T_w_c T_BS^-1."""
    sensor = glob.glob(os.path.join(seq, "**", "cam0", "sensor.yaml"), recursive=True)[0]
    text = open(sensor).read()
    start = text.index("T_BS:")
    end = text.index("]", text.index("data:", start)) + 1
    data = ", ".join("%.15g" % v for v in T_BS_EUROC.ravel())
    text = text[:start] + "T_BS:\n  cols: 4\n  rows: 4\n  data: [" + data + "]" + text[end:]
    open(sensor, "w").write(text)
    T_cb = np.linalg.inv(T_BS_EUROC)
    gt = glob.glob(os.path.join(seq, "groundtruth*tum*"))[0]
    with open(gt) as f, open(os.path.join(seq, "mav0", "state_groundtruth_estimate0", "data.csv"), "w") as out:
        out.write("#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], q_RS_y [], q_RS_z []\n")
        for line in f:
            if line.startswith("#") or not line.strip():
                continue
            v = line.split()
            sec, frac = v[0].split(".")
            ns = int(sec) * 10**9 + int(frac.ljust(9, "0")[:9])
            T = np.eye(4)
            T[:3, :3] = rot_of_quat(*[float(a) for a in v[4:8]])
            T[:3, 3] = [float(a) for a in v[1:4]]
            T_wb = T @ T_cb
            x, y, z, w = quat(T_wb[:3, :3])
            out.write("%d,%.9f,%.9f,%.9f,%.9f,%.9f,%.9f,%.9f\n" % ((ns,) + tuple(T_wb[:3, 3]) + (w, x, y, z)))


def generate(out_dir, frames, generator, make_bag):
    seq = os.path.join(out_dir, "generated")
    shutil.rmtree(seq, ignore_errors=True)
    subprocess.check_call([generator, "--out", seq, "--frames", str(frames), "--width", str(WIDTH),
                           "--height", str(HEIGHT)])
    subprocess.check_call([make_bag, seq, os.path.join(out_dir, "sequence.bag")])
    sensor = glob.glob(os.path.join(seq, "**", "cam0", "sensor.yaml"), recursive=True)
    gt = glob.glob(os.path.join(seq, "groundtruth*tum*"))
    if not sensor or not gt:
        sys.exit("make_test_bag.py: generator output lacks cam0/sensor.yaml or a groundtruth .tum")
    # The generator's own calibration (body = camera): the wrong T_BS for sensors.bag's IMU.
    shutil.copy(sensor[0], os.path.join(out_dir, "calibration_camera_body.yaml"))
    use_euroc_body(seq)
    subprocess.check_call([make_bag, seq, os.path.join(out_dir, "sensors.bag"), "--imu", "--compressed", "jpeg",
                           "--camera-info", "--rectified"])
    shutil.copy(sensor[0], os.path.join(out_dir, "calibration.yaml"))
    shutil.copy(gt[0], os.path.join(out_dir, "groundtruth.tum"))


def generate_long(out_dir, frames, generator, make_bag):
    """OUT_DIR/long.bag: the generator's room, `frames` frames (the camera goes on around the
    room: the mesh grows), OUT_DIR/long_calibration.yaml and OUT_DIR/long_groundtruth.tum."""
    seq = os.path.join(out_dir, "generated_long")
    shutil.rmtree(seq, ignore_errors=True)
    subprocess.check_call([generator, "--out", seq, "--frames", str(frames), "--width", str(WIDTH),
                           "--height", str(HEIGHT)])
    subprocess.check_call([make_bag, seq, os.path.join(out_dir, "long.bag")])
    sensor = glob.glob(os.path.join(seq, "**", "cam0", "sensor.yaml"), recursive=True)
    gt = glob.glob(os.path.join(seq, "groundtruth*tum*"))
    if not sensor or not gt:
        sys.exit("make_test_bag.py: generator output lacks cam0/sensor.yaml or a groundtruth .tum")
    shutil.copy(sensor[0], os.path.join(out_dir, "long_calibration.yaml"))
    shutil.copy(gt[0], os.path.join(out_dir, "long_groundtruth.tum"))
    shutil.rmtree(seq, ignore_errors=True)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("out_dir")
    parser.add_argument("--frames", type=int, default=60)
    parser.add_argument("--long-frames", type=int, default=0,
                        help="also long.bag of this many frames (needs --generator)")
    parser.add_argument("--generator", default="")
    parser.add_argument("--make-bag", default="")
    args = parser.parse_args()
    os.makedirs(args.out_dir, exist_ok=True)
    if args.generator and os.path.exists(args.generator):
        generate(args.out_dir, args.frames, args.generator, args.make_bag)
        if args.long_frames > 0:
            generate_long(args.out_dir, args.long_frames, args.generator, args.make_bag)
    else:
        draw(args.out_dir, args.frames)
        if args.long_frames > 0:
            tmp = os.path.join(args.out_dir, "drawn_long")
            os.makedirs(tmp, exist_ok=True)
            draw(tmp, args.long_frames)
            shutil.move(os.path.join(tmp, "sequence.bag"), os.path.join(args.out_dir, "long.bag"))
            shutil.move(os.path.join(tmp, "calibration.yaml"), os.path.join(args.out_dir, "long_calibration.yaml"))
            shutil.move(os.path.join(tmp, "groundtruth.tum"), os.path.join(args.out_dir, "long_groundtruth.tum"))
            shutil.rmtree(tmp, ignore_errors=True)
    print("make_test_bag.py: %d frames in %s" % (args.frames, args.out_dir))


if __name__ == "__main__":
    main()
