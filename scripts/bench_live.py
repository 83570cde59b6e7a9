#!/usr/bin/python3
"""The runs of scripts/bench_live.sh (see there): one master, per run a live.launch, a
`rosbag play` without --clock, this node listening to the images and the tracker's status."""
import argparse
import json
import os
import signal
import socket
import struct
import subprocess
import sys
import threading
import time

import numpy as np


def free_port():
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    return port


class Listener:
    """Wall arrival times of the images (by stamp), the tracker's poses and its statuses."""

    def __init__(self, rospy, image_topic):
        from geometry_msgs.msg import PoseStamped
        from vitamin_e.msg import TrackingStatus
        self.lock = threading.Lock()
        self.reset()
        # AnyMsg: the image is not deserialized, its stamp is read from the header's bytes.
        rospy.Subscriber(image_topic, rospy.AnyMsg, self.on_image, queue_size=1000, buff_size=2 ** 24)
        rospy.Subscriber("/tracking/status", TrackingStatus, self.on_status, queue_size=1000)
        rospy.Subscriber("/tracking/pose", PoseStamped, self.on_pose, queue_size=1000)

    def reset(self):
        with self.lock:
            self.images = {}
            self.statuses = []
            self.poses = {}
            self.last_status_wall = 0.0

    def on_image(self, msg):
        now = time.monotonic()
        _seq, sec, nsec = struct.unpack_from("<III", msg._buff, 0)
        with self.lock:
            self.images[sec * 10 ** 9 + nsec] = now

    def on_pose(self, msg):
        now = time.monotonic()
        with self.lock:
            self.poses.setdefault(msg.header.stamp.to_nsec(), now)

    def on_status(self, msg):
        now = time.monotonic()
        with self.lock:
            self.statuses.append((msg.header.stamp.to_nsec(), now, msg.state, msg.frames_processed,
                                  msg.frames_tracked, msg.relocalizations, msg.init_retries))
            self.last_status_wall = now


def run_once(args, rospy, listener, bag, calibration, mode, load, log_dir):
    listener.reset()
    launch_log = open(os.path.join(log_dir, "%s_%s_launch.log" % (mode, load)), "w")
    launch = subprocess.Popen(
        ["roslaunch", "vitamin_e", "live.launch", "image:=" + args.topic, "calibration_file:=" + calibration,
         "pipelined:=" + ("true" if mode == "pipelined" else "false")],
        stdout=launch_log, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL)
    busy = None
    try:
        deadline = time.monotonic() + 60
        while not rospy.is_shutdown() and time.monotonic() < deadline:
            published = [t for t, _ in rospy.get_published_topics()]
            if "/tracking/status" in published and "/tsdf_meshing/mesh" in published:
                break
            time.sleep(0.5)
        else:
            raise RuntimeError("live.launch did not come up (see %s)" % launch_log.name)
        time.sleep(3.0)  # subscriptions connected
        if load == "busy":
            busy = subprocess.Popen(["yes"], stdout=subprocess.DEVNULL)
        subprocess.check_call(["rosbag", "play", "--quiet", bag], stdin=subprocess.DEVNULL,
                              stdout=subprocess.DEVNULL)
        # The last statuses: until none came for 2 s.
        while time.monotonic() - max(listener.last_status_wall, 0.0) < 2.0:
            time.sleep(0.2)
    finally:
        if busy:
            busy.terminate()
            busy.wait()
        launch.send_signal(signal.SIGINT)
        try:
            launch.wait(timeout=60)
        except subprocess.TimeoutExpired:
            launch.kill()
            launch.wait()
        launch_log.close()
    with listener.lock:
        images = dict(listener.images)
        statuses = list(listener.statuses)
        poses = dict(listener.poses)
    # A frame's pose goes out before the rest of its result (its status among them).
    latency = [1000.0 * (wall - images[stamp]) for stamp, wall in poses.items() if stamp in images]
    status_latency = [1000.0 * (wall - images[stamp]) for stamp, wall, *_ in statuses if stamp in images]
    last = statuses[-1] if statuses else (0, 0, -1, 0, 0, -1, -1)
    n = len(images)
    return {
        "mode": mode, "load": load, "images": n, "processed": len(statuses),
        "drops_pct": 100.0 * (1.0 - len(statuses) / n) if n else float("nan"),
        "relocalizations": last[5], "init_retries": last[6],
        "tracked": last[4], "frames_processed": last[3],
        "latency_p50_ms": float(np.percentile(latency, 50)) if latency else float("nan"),
        "latency_p95_ms": float(np.percentile(latency, 95)) if latency else float("nan"),
        "latency_max_ms": float(max(latency)) if latency else float("nan"),
        "status_latency_p95_ms": float(np.percentile(status_latency, 95)) if status_latency else float("nan"),
    }


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--default-render", required=True)
    ap.add_argument("--make-bag", required=True)
    ap.add_argument("--default-out", required=True)
    ap.add_argument("--render", default="")
    ap.add_argument("--bag", default="")
    ap.add_argument("--calibration", default="")
    ap.add_argument("--topic", default="/cam0/image_raw")
    ap.add_argument("--modes", default="sequential,pipelined")
    ap.add_argument("--loads", default="idle,busy")
    ap.add_argument("--runs", type=int, default=1)
    ap.add_argument("--out", default="")
    args = ap.parse_args()
    out = args.out or args.default_out
    os.makedirs(out, exist_ok=True)
    render = args.render or args.default_render
    if args.bag:
        bag, calibration = args.bag, args.calibration
        if not calibration:
            sys.exit("bench_live: --bag needs --calibration")
    else:
        calibration = os.path.join(render, "mav0", "cam0", "sensor.yaml")
        bag = os.path.join(out, os.path.basename(os.path.normpath(render)) + ".bag")
        if not os.path.exists(bag):
            subprocess.check_call([args.make_bag, render, bag])
    for path in (bag, calibration):
        if not os.path.exists(path):
            sys.exit("bench_live: %s does not exist" % path)

    port = free_port()
    os.environ["ROS_MASTER_URI"] = "http://localhost:%d" % port
    core = subprocess.Popen(["roscore", "-p", str(port)], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                            stdin=subprocess.DEVNULL)
    results = []
    uptime_before = subprocess.check_output(["uptime"], text=True).strip()
    try:
        import rospy
        time.sleep(3.0)
        rospy.init_node("bench_live", anonymous=True, disable_signals=True)
        listener = Listener(rospy, args.topic)
        for load in args.loads.split(","):
            for _ in range(args.runs):
                for mode in args.modes.split(","):
                    r = run_once(args, rospy, listener, bag, calibration, mode, load, out)
                    r["uptime"] = subprocess.check_output(["uptime"], text=True).strip()
                    print("%s %s: %s" % (mode, load, json.dumps(r)), file=sys.stderr, flush=True)
                    results.append(r)
    finally:
        core.send_signal(signal.SIGINT)
        core.wait(timeout=30)
    uptime_after = subprocess.check_output(["uptime"], text=True).strip()
    print("bag: %s (%s)" % (bag, calibration))
    print("uptime before: %s" % uptime_before)
    print("uptime after:  %s" % uptime_after)
    print("| tracker | load | images | processed | dropped % | relocalizations | re-inits | tracked / processed "
          "| pose latency p50 ms | p95 ms | max ms | status latency p95 ms | uptime after the run |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for r in results:
        print("| %s | %s | %d | %d | %.1f | %d | %d | %d / %d | %.0f | %.0f | %.0f | %.0f | %s |" % (
            r["mode"], r["load"], r["images"], r["processed"], r["drops_pct"], r["relocalizations"],
            r["init_retries"], r["tracked"], r["frames_processed"], r["latency_p50_ms"], r["latency_p95_ms"],
            r["latency_max_ms"], r["status_latency_p95_ms"], r["uptime"].split("load average:")[-1].strip()))
    print(json.dumps({"bag": bag, "uptime_before": uptime_before, "uptime_after": uptime_after, "runs": results}))


if __name__ == "__main__":
    main()
