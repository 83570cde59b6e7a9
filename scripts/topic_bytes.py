#!/usr/bin/python3
"""Records the size of every message on a topic (serialized bytes, as on the wire)
until it is stopped (SIGINT / SIGTERM / the master going away), then writes a JSON
summary: messages, bytes, bytes per second over the run and per window of wall time,
the largest message.

    topic_bytes.py TOPIC OUT.json [--window S]

Subscribes with rospy.AnyMsg (no message class needed, nothing deserialized).
"""
import argparse
import json
import signal
import sys
import threading
import time

import rospy


def summarize(samples, window):
    """samples: [(wall time, bytes)] in arrival order."""
    out = {"messages": len(samples), "bytes": sum(b for _, b in samples)}
    if not samples:
        return out
    t0, t1 = samples[0][0], samples[-1][0]
    out["first_to_last_s"] = t1 - t0
    out["max_message_bytes"] = max(b for _, b in samples)
    out["bytes_per_s"] = out["bytes"] / (t1 - t0) if t1 > t0 else None
    # Bytes per window of wall time from the first message on (the last, partial, window left out).
    windows = []
    n = int((t1 - t0) // window)
    for k in range(n):
        lo, hi = t0 + k * window, t0 + (k + 1) * window
        windows.append(sum(b for t, b in samples if lo <= t < hi) / window)
    out["window_s"] = window
    out["bytes_per_s_by_window"] = windows
    if len(windows) >= 3:
        third = len(windows) // 3
        out["bytes_per_s_thirds"] = [
            sum(windows[:third]) / third,
            sum(windows[third:len(windows) - third]) / (len(windows) - 2 * third),
            sum(windows[len(windows) - third:]) / third,
        ]
    out["message_bytes"] = [b for _, b in samples]
    out["message_wall_s"] = [round(t - t0, 3) for t, _ in samples]
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("topic")
    ap.add_argument("out")
    ap.add_argument("--window", type=float, default=5.0)
    args = ap.parse_args(rospy.myargv()[1:])
    samples = []
    lock = threading.Lock()

    def callback(msg):
        with lock:
            samples.append((time.time(), len(msg._buff)))

    rospy.init_node("topic_bytes", anonymous=True, disable_signals=True)
    rospy.Subscriber(args.topic, rospy.AnyMsg, callback, queue_size=1000, buff_size=1 << 26)
    stop = threading.Event()
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda *_: stop.set())
    while not stop.is_set() and not rospy.is_shutdown():
        stop.wait(0.2)
    with lock:
        summary = summarize(list(samples), args.window)
    summary["topic"] = args.topic
    with open(args.out, "w") as f:
        json.dump(summary, f)
    rospy.signal_shutdown("done")
    return 0


if __name__ == "__main__":
    sys.exit(main())
