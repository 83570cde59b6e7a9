#!/usr/bin/python3
"""Plays a bag into vitamin_e and ends when the tracker has processed every frame.

A launch with `rosbag play` as the required node ends when the bag ends, and the
frames still queued in the tracker are lost. This node plays the bag (rosbag play
as a subprocess, same arguments), then waits until the tracker's ~status reports
that the last image of the bag was processed (or no progress for --idle-timeout s),
and exits: as a required node it then ends the launch.

  play_bag.py BAG [--rate R] [--start S] [--topic T] [--also TOPIC ...] [--status /tracking/status]
              [--idle-timeout S]

--also: more topics played with the images (e.g. /imu0); a topic the bag lacks is skipped.
"""
import argparse
import subprocess
import sys
import threading
import time

if __name__ == "__main__" and any(a in ("-h", "--help") for a in sys.argv[1:]):
    sys.stdout.write(__doc__)  # before the ROS imports: the usage needs no workspace
    sys.exit(0)

import rosbag
import rospy
from vitamin_e.msg import TrackingStatus


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("bag")
    ap.add_argument("--rate", type=float, default=1.0)
    ap.add_argument("--start", type=float, default=0.0)
    ap.add_argument("--topic", default="/cam0/image_raw")
    ap.add_argument("--status", default="/tracking/status")
    ap.add_argument("--also", nargs="*", default=[])
    ap.add_argument("--idle-timeout", type=float, default=10.0)
    args = ap.parse_args(rospy.myargv()[1:])

    try:
        with rosbag.Bag(args.bag) as bag:
            stamps = [t.to_sec() for _, _, t in bag.read_messages(topics=[args.topic])]
            in_bag = set(bag.get_type_and_topic_info().topics.keys())
    except Exception as e:  # unreadable or truncated bag: one clear line
        print("error: cannot read bag %s: %s" % (args.bag, e), file=sys.stderr)
        sys.exit(2)
    if not stamps:
        print("error: bag %s has no messages on %s" % (args.bag, args.topic), file=sys.stderr)
        sys.exit(2)
    expected = sum(1 for t in stamps if t >= stamps[0] + args.start)

    rospy.init_node("player", disable_signals=True)
    lock = threading.Lock()
    state = {"processed": 0, "last_change": time.monotonic()}

    def on_status(msg):
        with lock:
            if msg.frames_processed != state["processed"]:
                state["processed"] = msg.frames_processed
                state["last_change"] = time.monotonic()

    rospy.Subscriber(args.status, TrackingStatus, on_status, queue_size=100)
    also = [t for t in args.also if t and t != args.topic and t in in_bag]
    cmd = ["rosbag", "play", "--clock", "--quiet", "-r", str(args.rate), "-s", str(args.start),
           "--wait-for-subscribers", args.bag, "--topics", args.topic] + also
    rc = subprocess.call(cmd)
    if rc != 0:
        print("error: rosbag play exited with %d" % rc, file=sys.stderr)
        sys.exit(rc)
    # The bag has ended: wait for the tracker to drain its queue.
    with lock:
        state["last_change"] = time.monotonic()
    while not rospy.is_shutdown():
        with lock:
            done = state["processed"] >= expected
            idle = time.monotonic() - state["last_change"]
        if done:
            rospy.loginfo("all %d frames of the bag processed", expected)
            break
        if idle > args.idle_timeout:
            rospy.logwarn("bag ended; the tracker processed %d of %d frames and made no progress for %.0f s",
                          state["processed"], expected, idle)
            break
        time.sleep(0.1)
    time.sleep(0.5)  # let the last status and tf reach their subscribers


if __name__ == "__main__":
    main()
