#!/usr/bin/python3
"""Writes a EuRoC ASL folder's cam0 images into a rosbag.

    scripts/make_bag.sh ASL_FOLDER OUT.bag [--topic /cam0/image_raw] [--frame-id cam0]
                        [--camera cam0] [--max-frames N]

ASL_FOLDER is a sequence folder (containing mav0/) or its mav0/ folder. Each row
of <camera>/data.csv ("timestamp [ns], filename") becomes one sensor_msgs/Image
(mono8; colour or 16-bit images are converted) stamped with the row's exact
nanoseconds, written at that time. A python3 script run by /usr/bin/python3
(Debian's rosbag module; the pyenv python on PATH lacks it).
"""
import argparse
import csv
import os
import sys

import cv2
import rosbag
import rospy
from sensor_msgs.msg import Image


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


def to_mono8(image):
    if image.ndim == 3:
        code = cv2.COLOR_BGRA2GRAY if image.shape[2] == 4 else cv2.COLOR_BGR2GRAY
        image = cv2.cvtColor(image, code)
    if image.dtype != "uint8":
        image = (image >> 8).astype("uint8")
    return image


def main():
    parser = argparse.ArgumentParser(description="EuRoC ASL cam0 images -> rosbag (sensor_msgs/Image mono8)")
    parser.add_argument("asl_folder")
    parser.add_argument("out_bag")
    parser.add_argument("--topic", default="/cam0/image_raw")
    parser.add_argument("--frame-id", default="cam0")
    parser.add_argument("--camera", default="cam0")
    parser.add_argument("--max-frames", type=int, default=0, help="0: all")
    args = parser.parse_args()

    cam_dir = find_camera_dir(args.asl_folder, args.camera)
    rows = read_rows(os.path.join(cam_dir, "data.csv"))
    if args.max_frames > 0:
        rows = rows[:args.max_frames]
    if not rows:
        sys.exit("make_bag.sh: no images listed in %s/data.csv" % cam_dir)

    written = 0
    with rosbag.Bag(args.out_bag, "w") as bag:
        for seq, (ns, name) in enumerate(rows):
            path = os.path.join(cam_dir, "data", name)
            image = cv2.imread(path, cv2.IMREAD_UNCHANGED)
            if image is None:
                sys.exit("make_bag.sh: cannot read image %s" % path)
            image = to_mono8(image)
            stamp = rospy.Time(ns // 1000000000, ns % 1000000000)
            msg = Image()
            msg.header.seq = seq
            msg.header.stamp = stamp
            msg.header.frame_id = args.frame_id
            msg.height, msg.width = image.shape[:2]
            msg.encoding = "mono8"
            msg.is_bigendian = 0
            msg.step = msg.width
            msg.data = image.tobytes()
            bag.write(args.topic, msg, t=stamp)
            written += 1
    print("make_bag.sh: %d images from %s -> %s (%s)" % (written, cam_dir, args.out_bag, args.topic))


if __name__ == "__main__":
    main()
