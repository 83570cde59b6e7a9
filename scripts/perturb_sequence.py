#!/usr/bin/python3
"""Copies an EuRoC ASL sequence with some frames made hard, for robustness benchmarks.

    ./scripts/perturb_sequence.py SRC OUT [--black START_S DURATION_S] [--upside-down-from S]
                                          [--max-s S]

SRC: a sequence folder with mav0/cam0/data.csv (a render of the shared renderer or
of vitamin_e_make_sequence). OUT gets the same layout: unchanged images are
symlinked, changed ones written:
  --black START_S DURATION_S   frames from START_S (seconds after the first frame)
                               for DURATION_S are black (a lens cap, a tunnel)
  --upside-down-from S         frames from S on are turned by 180 degrees (the camera
                               rolled upside down; the ground-truth positions stay valid)
  --max-s S                    keep only the first S seconds
Ground truth (groundtruth_cam0_tum.txt, state_groundtruth_estimate0) and the
sensor.yaml are copied, so ./scripts/evaluate.sh OUT/... works on the result.
"""
import argparse
import os
import shutil
import sys

import cv2
import numpy as np


def fail(msg):
    print("error: " + msg, file=sys.stderr)
    sys.exit(2)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("src")
    ap.add_argument("out")
    ap.add_argument("--black", nargs=2, type=float, metavar=("START_S", "DURATION_S"))
    ap.add_argument("--upside-down-from", type=float, metavar="S")
    ap.add_argument("--max-s", type=float, metavar="S")
    a = ap.parse_args()

    cam = os.path.join(a.src, "mav0", "cam0")
    csv = os.path.join(cam, "data.csv")
    if not os.path.isfile(csv):
        fail("%s: no mav0/cam0/data.csv (not an EuRoC ASL sequence)" % a.src)
    if os.path.abspath(a.src) == os.path.abspath(a.out):
        fail("OUT must differ from SRC")
    rows = []
    with open(csv) as fh:
        for line in fh:
            if line.startswith("#") or not line.strip():
                continue
            stamp, name = [x.strip() for x in line.split(",")[:2]]
            rows.append((int(stamp), name))
    if not rows:
        fail("%s lists no images" % csv)
    t0 = rows[0][0]

    out_cam = os.path.join(a.out, "mav0", "cam0")
    os.makedirs(os.path.join(out_cam, "data"), exist_ok=True)
    kept = []
    black = upside = 0
    for stamp, name in rows:
        t = (stamp - t0) * 1e-9
        if a.max_s is not None and t > a.max_s:
            break
        src_img = os.path.abspath(os.path.join(cam, "data", name))
        dst_img = os.path.join(out_cam, "data", name)
        if os.path.lexists(dst_img):
            os.remove(dst_img)
        is_black = a.black is not None and a.black[0] <= t < a.black[0] + a.black[1]
        is_upside = a.upside_down_from is not None and t >= a.upside_down_from
        if is_black or is_upside:
            img = cv2.imread(src_img, cv2.IMREAD_UNCHANGED)
            if img is None:
                fail("cannot read %s" % src_img)
            if is_black:
                img = np.zeros_like(img)
                black += 1
            else:
                img = cv2.rotate(img, cv2.ROTATE_180)
                upside += 1
            if not cv2.imwrite(dst_img, img):
                fail("cannot write %s" % dst_img)
        else:
            os.symlink(src_img, dst_img)
        kept.append((stamp, name))
    with open(os.path.join(out_cam, "data.csv"), "w") as fh:
        fh.write("#timestamp [ns],filename\n")
        for stamp, name in kept:
            fh.write("%d,%s\n" % (stamp, name))
    for f in ("sensor.yaml",):
        if os.path.isfile(os.path.join(cam, f)):
            shutil.copy(os.path.join(cam, f), os.path.join(out_cam, f))
    gt_dir = os.path.join(a.src, "mav0", "state_groundtruth_estimate0")
    if os.path.isdir(gt_dir):
        shutil.copytree(gt_dir, os.path.join(a.out, "mav0", "state_groundtruth_estimate0"), dirs_exist_ok=True)
    for f in ("groundtruth_cam0_tum.txt", "scene.json"):
        if os.path.isfile(os.path.join(a.src, f)):
            shutil.copy(os.path.join(a.src, f), os.path.join(a.out, f))
    print("%s: %d frames (%d black, %d upside down)" % (a.out, len(kept), black, upside))


if __name__ == "__main__":
    main()
