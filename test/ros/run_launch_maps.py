#!/usr/bin/python3
"""Maps through the launch files, as a user runs them (each roslaunch with its own master):

 1. euroc.launch save_map:=FILE on the test bag: the map file is written when the bag ends.
 2. live.launch ns:=cam_a load_map:=FILE localization_only:=true (use_sim_time, every frame),
    the bag played by rosbag play --clock: the tracker relocalizes in the loaded map and
    tracks in it (status "localizing in loaded map", never initialized), its saved trajectory
    is close to the ground truth, the map file is unchanged, the node is /cam_a/tracking, and
    no deprecation warning is logged.
 3. live.launch load_map:=<a damaged file>: the tracker's FATAL says why, its load fails, and
    the launch ends by itself (required), instead of running on with nothing subscribed.

    run_launch_maps.py --data DIR --out DIR --evaluate PATH [--timeout S]

Exit 0 when every check passes; the last line is a JSON summary.
"""
import argparse
import hashlib
import json
import os
import signal
import socket
import subprocess
import sys
import time


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def ros_env(out, port):
    env = dict(os.environ)
    env["PATH"] = "/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin"
    env["ROS_MASTER_URI"] = "http://localhost:%d" % port
    env["ROS_IP"] = "127.0.0.1"
    env["ROS_HOSTNAME"] = "localhost"
    env["ROS_HOME"] = os.path.join(out, "ros_home")
    env["ROS_LOG_DIR"] = os.path.join(out, "ros_home", "log")
    return env


def stop(proc, timeout=30):
    """SIGINT to the launch's process group, as Ctrl-C; returns its exit code."""
    if proc.poll() is None:
        os.killpg(proc.pid, signal.SIGINT)
        try:
            proc.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    return proc.returncode


def launch(args, out, name, env):
    log = open(os.path.join(out, name + ".log"), "w")
    proc = subprocess.Popen(["roslaunch", "-p", env["ROS_MASTER_URI"].rsplit(":", 1)[1]] + args, env=env, stdout=log,
                            stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL, start_new_session=True)
    return proc, log.name


def read(path):
    with open(path, errors="replace") as f:
        return f.read()


def digest(path):
    with open(path, "rb") as f:
        return hashlib.sha256(f.read()).hexdigest()


def count_poses(path):
    return sum(1 for line in open(path) if line.strip() and not line.startswith("#"))


def save_map(a, env, failures):
    bag = os.path.join(a.data, "sequence.bag")
    calib = os.path.join(a.data, "calibration.yaml")
    map_path = os.path.join(a.out, "map.vemap")
    if os.path.exists(map_path):
        os.remove(map_path)
    proc, log = launch(["vitamin_e", "euroc.launch", "bag:=" + bag, "rviz:=false", "calibration_file:=" + calib,
                        "save_map:=" + map_path], a.out, "save_map", env)
    try:
        proc.wait(timeout=a.timeout)
    except subprocess.TimeoutExpired:
        stop(proc)
        sys.exit("run_launch_maps.py: euroc.launch save_map:= did not end within %.0f s (log %s)" % (a.timeout, log))
    if not os.path.isfile(map_path):
        sys.exit("run_launch_maps.py: euroc.launch save_map:=%s wrote no map (log %s):\n%s" %
                 (map_path, log, read(log)[-3000:]))
    return map_path


def localize(a, env, map_path, failures, result):
    import rosgraph
    import rospy
    from vitamin_e.msg import TrackingStatus
    bag = os.path.join(a.data, "sequence.bag")
    calib = os.path.join(a.data, "calibration.yaml")
    traj = os.path.join(a.out, "localized_trajectory.txt")
    if os.path.exists(traj):
        os.remove(traj)
    before = digest(map_path)
    proc, log = launch(["vitamin_e", "live.launch", "ns:=cam_a", "image:=/cam0/image_raw", "calibration_file:=" + calib,
                        "load_map:=" + map_path, "localization_only:=true", "use_sim_time:=true",
                        "process_all_frames:=true", "trajectory_file:=" + traj], a.out, "localize", env)
    os.environ.update({k: env[k] for k in ("ROS_MASTER_URI", "ROS_IP", "ROS_HOSTNAME", "ROS_HOME", "ROS_LOG_DIR")})
    statuses = []
    try:
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline and proc.poll() is None:
            try:
                rosgraph.Master("/run_launch_maps").getPid()
                break
            except Exception:
                time.sleep(0.2)
        rospy.init_node("run_launch_maps", anonymous=True, disable_signals=True)
        rospy.Subscriber("/cam_a/tracking/status", TrackingStatus, statuses.append, queue_size=1000)
        frames = sum(1 for _ in open(os.path.join(a.data, "groundtruth.tum")) if not _.startswith("#"))
        play = subprocess.run(["rosbag", "play", "--clock", "--quiet", "--wait-for-subscribers", bag], env=env,
                              stdout=subprocess.DEVNULL, stderr=subprocess.STDOUT, timeout=a.timeout)
        if play.returncode != 0:
            failures.append("rosbag play exited with %d" % play.returncode)
        deadline = time.monotonic() + a.timeout
        while time.monotonic() < deadline and (not statuses or statuses[-1].frames_processed < frames):
            time.sleep(0.2)
        nodes = rosgraph.Master("/run_launch_maps").getSystemState()
        names = set(n for group in nodes for _, members in group for n in members)
        if "/cam_a/tracking" not in names:
            failures.append("ns:=cam_a: no node /cam_a/tracking (nodes: %s)" % sorted(names))
    finally:
        rc = stop(proc)
    text = read(log)
    result["localized_frames"] = statuses[-1].frames_processed if statuses else 0
    if "relocalizing in the loaded map" not in text:
        failures.append("live.launch load_map:= did not load the map (log %s)" % log)
    localizing = [s for s in statuses if s.message.startswith("localizing in loaded map")]
    initialized = [s for s in statuses if s.message.startswith("initialized")]
    result["localizing_statuses"] = len(localizing)
    if len(localizing) < 30:
        failures.append("%d statuses 'localizing in loaded map' of %d" % (len(localizing), len(statuses)))
    if initialized:
        failures.append("a new map was initialized although a map was loaded")
    if "~map_file" in text:
        failures.append("a ~map_file deprecation warning on a plain start (log %s)" % log)
    if digest(map_path) != before:
        failures.append("localization only changed the map file")
    if not os.path.isfile(traj):
        failures.append("no trajectory written on shutdown (exit %s, log %s)" % (rc, log))
        return
    result["localized_poses"] = count_poses(traj)
    out = subprocess.run([a.evaluate, traj, os.path.join(a.data, "groundtruth.tum"), "--json"], capture_output=True,
                         text=True)
    if out.returncode != 0:
        failures.append("vitamin_e_evaluate failed: %s" % out.stderr.strip())
        return
    ate = json.loads(out.stdout.strip().splitlines()[-1])["ate_rmse_m"]
    result["localized_ate_rmse_m"] = ate
    if not ate < 0.01:
        failures.append("ATE of the localized run %.4f m (bound 0.01)" % ate)


def damaged(a, env, map_path, failures, result):
    bad = os.path.join(a.out, "damaged.vemap")
    data = open(map_path, "rb").read()
    with open(bad, "wb") as f:
        f.write(data[:len(data) // 2])  # cut in half, as a copy that did not finish
    calib = os.path.join(a.data, "calibration.yaml")
    proc, log = launch(["vitamin_e", "live.launch", "image:=/cam0/image_raw", "calibration_file:=" + calib,
                        "load_map:=" + bad], a.out, "damaged", env)
    t0 = time.monotonic()
    try:
        proc.wait(timeout=90)
    except subprocess.TimeoutExpired:
        stop(proc)
        failures.append("live.launch load_map:=<damaged> did not end by itself within 90 s (log %s)" % log)
        return
    result["damaged_launch_s"] = round(time.monotonic() - t0, 1)
    text = read(log)
    if "~load_map" not in text:
        failures.append("no FATAL naming ~load_map (log %s)" % log)
    if "REQUIRED process [tracking" not in text:
        failures.append("roslaunch did not report the tracker's load as failed (log %s)" % log)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--data", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--evaluate", required=True)
    ap.add_argument("--timeout", type=float, default=240.0)
    a = ap.parse_args()
    a.data, a.out = os.path.abspath(a.data), os.path.abspath(a.out)
    os.makedirs(a.out, exist_ok=True)
    failures, result = [], {}
    map_path = save_map(a, ros_env(a.out, free_port()), failures)
    localize(a, ros_env(a.out, free_port()), map_path, failures, result)
    damaged(a, ros_env(a.out, free_port()), map_path, failures, result)
    for f in failures:
        print("FAIL: " + f)
    print(json.dumps(result))
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
