#!/usr/bin/python3
"""Runs `roslaunch vitamin_e euroc.launch` to its end on a test bag (its own master on a
free port) and checks the trajectory it writes.

    run_euroc_launch.py --data DIR --bag NAME --out DIR --evaluate PATH
        [--install BUILD_DIR]        build install/ (make install) and run from it
        [--downstream SRC_DIR]       with --install: build a package using libvitamin_e from
                                     install/ only (test/downstream) and run it
        [--max-tilt-deg D]           the map's z within D degrees of the true up
        [--compare-offline RUN_PATH] the ATE within 10 % of vitamin_e_run's on the same bag
        [--offline-arg=ARG ...]      more arguments of that vitamin_e_run (e.g. --offline-arg=--pipelined)
        [--offline-same]             the same poses as vitamin_e_run's: as many, at the same
                                     stamps, the positions the same to 10 nm once rotated into
                                     the launch's map frame (a rotation of the offline one)
        [--launch-arg NAME:=VALUE ...] more arguments of euroc.launch
        [--expect-log TEXT ...]      the launch's output must contain TEXT
        [--min-poses N] [--timeout S]

The map's tilt: vitamin_e_evaluate aligns the saved trajectory (T_map_c) to the ground
truth (z up) with a Sim(3); its rotation R maps the map's axes into the ground-truth world,
so the tilt is the angle between R e_z and e_z (R from the aligned and the saved
orientations of any pose). Exit 0 when every check passes; the last line is a JSON summary.
"""
import argparse
import json
import math
import os
import shutil
import signal
import socket
import subprocess
import sys
import time

import numpy as np


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def read_tum(path):
    rows = []
    with open(path) as f:
        for line in f:
            if line.startswith("#") or not line.strip():
                continue
            rows.append([float(v) for v in line.split()])
    return np.array(rows).reshape(-1, 8)


def rot(q):
    x, y, z, w = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def evaluate(evaluator, traj, gt, aligned):
    out = subprocess.run([evaluator, traj, gt, "--json", "--aligned-out", aligned], capture_output=True, text=True)
    if out.returncode != 0:
        sys.exit("run_euroc_launch.py: vitamin_e_evaluate failed: %s" % out.stderr.strip())
    return json.loads(out.stdout.strip().splitlines()[-1])


def max_rotated_difference(a, b):
    """The largest distance between the positions of a and b (same stamps) once b is rotated
    onto a about their centroids (Kabsch): 0 up to rounding when b is the same run in other axes."""
    pa, pb = a[:, 1:4] - a[:, 1:4].mean(axis=0), b[:, 1:4] - b[:, 1:4].mean(axis=0)
    u, _, vt = np.linalg.svd(pb.T @ pa)
    d = np.sign(np.linalg.det(u @ vt))
    r = (u @ np.diag([1.0, 1.0, d]) @ vt).T
    return float(np.max(np.linalg.norm(pa - pb @ r.T, axis=1)))


def tilt_deg(traj, aligned):
    est, al = read_tum(traj), read_tum(aligned)
    n = min(len(est), len(al))
    tilts = []
    for k in range(n):  # the same rotation for every pose: take the median
        R = rot(al[k, 4:8]) @ rot(est[k, 4:8]).T
        tilts.append(math.degrees(math.acos(max(-1.0, min(1.0, R[2, 2])))))
    return float(np.median(tilts))


def clean_env(env, out, port, install_only):
    env["PATH"] = "/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin"
    env["ROS_MASTER_URI"] = "http://localhost:%d" % port
    env["ROS_IP"] = "127.0.0.1"
    env["ROS_HOSTNAME"] = "localhost"
    env["ROS_HOME"] = os.path.join(out, "ros_home")
    env["ROS_LOG_DIR"] = os.path.join(out, "ros_home", "log")
    if install_only:
        # Only the install space: a clean environment for ROS, as from a fresh shell.
        for k in list(env):
            if k.startswith("ROS_PACKAGE_PATH") or k in ("CMAKE_PREFIX_PATH", "PYTHONPATH", "LD_LIBRARY_PATH",
                                                        "PKG_CONFIG_PATH", "ROSLISP_PACKAGE_DIRECTORIES"):
                del env[k]
    return env


def build_downstream(src, work, setup, env):
    """A catkin package outside the tree that links libvitamin_e from install/ and runs."""
    build = os.path.join(work, "build")
    shutil.rmtree(build, ignore_errors=True)  # configured afresh against this install/
    os.makedirs(build, exist_ok=True)
    log = os.path.join(work, "build.log")
    script = ('source "$0" && cmake -S "$1" -B "$2" -DCATKIN_DEVEL_PREFIX="$2/devel" '
              '-DPYTHON_EXECUTABLE=/usr/bin/python3 && make -C "$2" -j2 && "$2/devel/lib/vitamin_e_downstream/downstream_slam"')
    with open(log, "w") as f:
        rc = subprocess.call(["bash", "-c", script, setup, os.path.abspath(src), build], env=env, stdout=f,
                             stderr=subprocess.STDOUT)
    if rc != 0:
        sys.exit("run_euroc_launch.py: the downstream package did not build or run against install/ (%s):\n%s"
                 % (log, open(log).read()[-2500:]))
    print(open(log).read().strip().splitlines()[-1])


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--data", required=True)
    ap.add_argument("--bag", default="sequence.bag")
    ap.add_argument("--out", required=True)
    ap.add_argument("--evaluate", required=True)
    ap.add_argument("--install", default="")
    ap.add_argument("--downstream", default="")
    ap.add_argument("--max-tilt-deg", type=float, default=-1.0)
    ap.add_argument("--compare-offline", default="", help="vitamin_e_run, run with config/euroc.yaml as the launch")
    ap.add_argument("--offline-arg", action="append", default=[])
    ap.add_argument("--offline-same", action="store_true")
    ap.add_argument("--launch-arg", action="append", default=[])
    ap.add_argument("--expect-log", action="append", default=[])
    ap.add_argument("--min-poses", type=int, default=30)
    ap.add_argument("--timeout", type=float, default=240.0)
    args = ap.parse_args()
    args.data = os.path.abspath(args.data)
    args.out = os.path.abspath(args.out)
    os.makedirs(args.out, exist_ok=True)
    bag = os.path.join(args.data, args.bag)
    calib = os.path.join(args.data, "calibration.yaml")
    gt = os.path.join(args.data, "groundtruth.tum")
    traj = os.path.join(args.out, "trajectory.txt")
    if os.path.exists(traj):
        os.remove(traj)

    setup = ""
    if args.install:
        # The install space, as a user gets it: make install, then only install/setup.bash.
        log = os.path.join(args.out, "install.log")
        with open(log, "w") as f:
            rc = subprocess.call(["make", "-C", args.install, "install"], stdout=f, stderr=subprocess.STDOUT)
        if rc != 0:
            sys.exit("run_euroc_launch.py: make install failed (%s)" % log)
        prefix = None
        for line in open(os.path.join(args.install, "CMakeCache.txt")):
            if line.startswith("CMAKE_INSTALL_PREFIX:"):
                prefix = line.split("=", 1)[1].strip()
        setup = os.path.join(prefix, "setup.bash")
        if not os.path.isfile(setup):
            sys.exit("run_euroc_launch.py: no %s after make install" % setup)

    port = free_port()
    env = clean_env(dict(os.environ), args.out, port, bool(setup))
    if args.downstream:
        if not setup:
            sys.exit("run_euroc_launch.py: --downstream needs --install")
        build_downstream(args.downstream, os.path.join(args.out, "downstream"), setup, env)
    launch = ["roslaunch", "-p", str(port), "vitamin_e", "euroc.launch", "bag:=" + bag, "rviz:=false",
              "calibration_file:=" + calib, "trajectory_file:=" + traj,
              "mesh_file:=" + os.path.join(args.out, "mesh.ply")] + args.launch_arg
    if setup:
        cmd = ["bash", "-c", 'source "$0" && exec "$@"', setup] + launch
    else:
        cmd = launch
    log_path = os.path.join(args.out, "roslaunch.log")
    t0 = time.monotonic()
    with open(log_path, "w") as log:
        proc = subprocess.Popen(cmd, env=env, stdout=log, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                                start_new_session=True)
        try:
            rc = proc.wait(timeout=args.timeout)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGINT)
            try:
                proc.wait(timeout=20)
            except subprocess.TimeoutExpired:
                os.killpg(proc.pid, signal.SIGKILL)
            sys.exit("run_euroc_launch.py: euroc.launch did not end within %.0f s (log: %s)" % (args.timeout, log_path))
    seconds = time.monotonic() - t0
    if rc != 0:
        tail = open(log_path).read()[-3000:]
        sys.exit("run_euroc_launch.py: roslaunch exited with %d (log %s):\n%s" % (rc, log_path, tail))
    if not os.path.isfile(traj):
        sys.exit("run_euroc_launch.py: %s not written (log %s)" % (traj, log_path))
    poses = len(read_tum(traj))
    result = {"launch_s": round(seconds, 1), "poses": poses, "install": bool(args.install)}
    failures = []
    log_text = open(log_path, errors="replace").read()
    for text in args.expect_log:
        if text not in log_text:
            failures.append("the launch's output lacks '%s' (log %s)" % (text, log_path))
    if args.install:
        # The command-line tools come with the install space too (rosrun vitamin_e ...).
        prefix = os.path.dirname(setup)
        for tool in ("vitamin_e_run", "vitamin_e_make_sequence", "vitamin_e_evaluate", "vitamin_e_ros_params"):
            path = os.path.join(prefix, "lib", "vitamin_e", tool)
            if not os.access(path, os.X_OK):
                failures.append("%s not installed by make install" % path)
            elif subprocess.call([path, "--help"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL) != 0:
                failures.append("%s --help failed" % path)
    if poses < args.min_poses:
        failures.append("%d poses saved, expected >= %d" % (poses, args.min_poses))
    ev = evaluate(args.evaluate, traj, gt, os.path.join(args.out, "aligned.txt"))
    result["ate_rmse_m"] = ev["ate_rmse_m"]
    if args.max_tilt_deg >= 0:
        tilt = tilt_deg(traj, os.path.join(args.out, "aligned.txt"))
        result["map_z_tilt_deg"] = round(tilt, 3)
        if not tilt < args.max_tilt_deg:
            failures.append("the map's z is %.2f deg from the true up (limit %.1f)" % (tilt, args.max_tilt_deg))
    if args.compare_offline:
        off_dir = os.path.join(args.out, "offline")
        config = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "config", "euroc.yaml")
        rc = subprocess.call([args.compare_offline, "--dataset", bag, "--calib", calib, "--config", config,
                              "--out", off_dir, "--quiet"] + args.offline_arg)
        if rc != 0:
            sys.exit("run_euroc_launch.py: vitamin_e_run exited with %d" % rc)
        off = evaluate(args.evaluate, os.path.join(off_dir, "trajectory.txt"), gt, os.path.join(off_dir, "aligned.txt"))
        result["offline_ate_rmse_m"] = off["ate_rmse_m"]
        if args.offline_same:
            launched, offline = read_tum(traj), read_tum(os.path.join(off_dir, "trajectory.txt"))
            if launched.shape != offline.shape or not np.allclose(launched[:, 0], offline[:, 0], rtol=0, atol=1e-6):
                failures.append("%d poses through euroc.launch, %d offline, or other stamps: not the same run" %
                                (len(launched), len(offline)))
            else:
                result["offline_max_difference_m"] = max_rotated_difference(launched, offline)
                if not result["offline_max_difference_m"] < 1e-8:  # the files keep 1 nm
                    failures.append("positions up to %.3g m apart through euroc.launch and offline: not the same run"
                                    % result["offline_max_difference_m"])
        if not abs(ev["ate_rmse_m"] - off["ate_rmse_m"]) <= 0.1 * off["ate_rmse_m"]:
            failures.append("ATE %.5f m through euroc.launch vs %.5f m offline: more than 10 %% apart" %
                            (ev["ate_rmse_m"], off["ate_rmse_m"]))
    for f in failures:
        print("FAIL: " + f)
    print(json.dumps(result))
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
