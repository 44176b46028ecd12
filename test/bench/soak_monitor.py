#!/usr/bin/env python3
"""Soak monitor: per-scan end-to-end latency (output receipt wall time minus the input's
header stamp, i.e. simulator publish -> perception -> output delivered), dropped scans (inputs
whose output never arrived), and the resident memory of the perception manager over time.

Usage: soak_monitor.py --duration SECONDS --pid MANAGER_PID [--json OUT]
Messages are received as raw bytes (rospy.AnyMsg): only the header is parsed, so the monitor
itself costs one serialisation per message and no deserialisation."""
import argparse
import json
import struct
import sys
import threading
import time

import rospy


def header_stamp(raw):
    # std_msgs/Header first: seq uint32, stamp secs uint32, nsecs uint32.
    _, secs, nsecs = struct.unpack_from('<III', raw, 0)
    return secs * 1000000000 + nsecs


class Stream:
    def __init__(self, name, input_topic, output_topic):
        self.name = name
        self.lock = threading.Lock()
        self.inputs = {}      # stamp -> receipt wall time
        self.latencies = []   # seconds
        self.outputs = 0
        self.unmatched_outputs = 0
        self.measuring = False
        rospy.Subscriber(input_topic, rospy.AnyMsg, self.on_input, queue_size=200,
                         buff_size=1 << 26, tcp_nodelay=True)
        rospy.Subscriber(output_topic, rospy.AnyMsg, self.on_output, queue_size=200,
                         buff_size=1 << 26, tcp_nodelay=True)

    def on_input(self, msg):
        if not self.measuring:
            return
        with self.lock:
            self.inputs[header_stamp(msg._buff)] = time.time()

    def on_output(self, msg):
        now = time.time()
        stamp = header_stamp(msg._buff)
        with self.lock:
            if stamp in self.inputs:
                self.latencies.append(now - stamp * 1e-9)
                del self.inputs[stamp]
                self.outputs += 1
            elif self.measuring:
                self.unmatched_outputs += 1

    def summary(self, grace):
        with self.lock:
            now = time.time()
            # Inputs still waiting after the grace period count as dropped.
            dropped = sum(1 for t in self.inputs.values() if now - t > grace)
            lat = sorted(self.latencies)
        def pct(p):
            return lat[min(len(lat) - 1, int(round(p / 100.0 * (len(lat) - 1))))] * 1e3 if lat else None
        return {
            'scans': len(lat) + dropped,
            'outputs': len(lat),
            'dropped': dropped,
            'latency_ms': {'p50': pct(50), 'p99': pct(99), 'max': lat[-1] * 1e3 if lat else None},
        }


def rss_kib(pid):
    with open('/proc/%d/status' % pid) as f:
        for line in f:
            if line.startswith('VmRSS:'):
                return int(line.split()[1])
    return None


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('--duration', type=float, default=600.0)
    ap.add_argument('--warmup', type=float, default=10.0)
    ap.add_argument('--pid', type=int, required=True)
    ap.add_argument('--json', default='')
    args = ap.parse_args(rospy.myargv()[1:])
    rospy.init_node('soak_monitor', anonymous=True)
    streams = [
        Stream('velodyne -> vertical_scan_ground', '/velodyne_points', '/vertical_scan_ground/classified'),
        Stream('sick_vertical -> hough_ground', '/sick_vertical/scan', '/hough_ground/classified'),
    ]
    time.sleep(args.warmup)  # connections up, first scans through
    for s in streams:
        s.measuring = True
    start = time.time()
    memory = []  # (seconds since start, RSS KiB)
    next_print = start
    while not rospy.is_shutdown() and time.time() - start < args.duration:
        t = time.time() - start
        memory.append((t, rss_kib(args.pid)))
        if time.time() >= next_print:
            print('t=%4.0fs RSS %.1f MiB, %s' % (t, memory[-1][1] / 1024.0, ', '.join(
                '%s: %d' % (s.name.split()[0], len(s.latencies)) for s in streams)), flush=True)
            next_print += 60.0
        time.sleep(1.0)
    for s in streams:
        s.measuring = False
    time.sleep(2.0)  # outputs of the last inputs
    after_first_minute = [m for t, m in memory if t >= 60.0]
    growth = None
    if len(after_first_minute) >= 2:
        base = after_first_minute[0]
        growth = (max(after_first_minute) - base) / float(base) * 100.0
    result = {
        'duration_s': args.duration,
        'streams': {s.name: s.summary(grace=2.0) for s in streams},
        'rss_mib': {
            'at_1min': after_first_minute[0] / 1024.0 if after_first_minute else None,
            'max_after_1min': max(after_first_minute) / 1024.0 if after_first_minute else None,
            'end': memory[-1][1] / 1024.0 if memory else None,
            'growth_after_1min_percent': growth,
        },
        'rss_samples_kib': memory[::10],
    }
    text = json.dumps(result, indent=2)
    print(text)
    if args.json:
        with open(args.json, 'w') as f:
            f.write(text)
    ok = all(v['dropped'] == 0 for v in result['streams'].values()) and \
        (growth is None or growth < 1.0)
    sys.exit(0 if ok else 1)


if __name__ == '__main__':
    main()
