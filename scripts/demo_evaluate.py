#!/usr/bin/python3
"""The demo's evaluator (run by scripts/demo next to launch/playback.launch).

While a simulated bag plays it pairs the nodelets' outputs with the simulator's truth by stamp:
  * /vertical_scan_ground/classified with /velodyne_points_truth (one `class` per point, same
    order): ground precision / recall and obstacle recall, with the truth mapping of
    include/ladar_perception/eval/ground_evaluation.h (road, sidewalk, terrain = ground;
    curb face, car, wall, pole/tree, person, pothole = obstacle; unknown counts as a miss);
  * /hough_ground/ground_fit with /sick_vertical/scan and its truth: the fit error is the height
    of the true-ground returns of the scan above the fitted line (in the ground frame, through
    the true mount of the scanner);
  * /diagnostics: the nodelets' processing time per scan.
When the bag has ended (/clock still for --idle seconds) it calls /calibration/calibrate with an
initial guess off the true extrinsic, compares the answer with the truth and writes everything
to --json. Exits non-zero with a message when a step has no result.
"""
import argparse
import json
import math
import subprocess
import sys
import threading
import time

import numpy as np
import rospy
import yaml
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import Transform
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import LaserScan, PointCloud2

from ladar_perception.msg import HoughGroundFit
from ladar_perception.srv import Calibrate, CalibrateRequest

GROUND_CLASSES = (0, 1, 2)            # road, sidewalk, terrain
OBSTACLE_CLASSES = (3, 4, 5, 6, 7, 8)  # curb face, car, wall, pole/tree, person, pothole
LABEL_GROUND, LABEL_OBSTACLE = 0, 1


def field_column(msg, name, dtype):
    """One field of every point as a numpy array (any point_step / field order)."""
    for f in msg.fields:
        if f.name == name:
            n = msg.width * msg.height
            raw = np.frombuffer(msg.data, dtype=np.uint8)[: n * msg.point_step]
            rows = raw.reshape(n, msg.point_step)
            size = np.dtype(dtype).itemsize
            return rows[:, f.offset:f.offset + size].copy().view(dtype).reshape(n)
    raise KeyError("no field '%s' in a cloud on %s" % (name, msg.header.frame_id))


def quat_matrix(x, y, z, w):
    n = math.sqrt(x * x + y * y + z * z + w * w)
    x, y, z, w = x / n, y / n, z / n, w / n
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def rpy_of(R):
    """roll, pitch, yaw as tf's getRPY (R = Rz(yaw) Ry(pitch) Rx(roll))."""
    pitch = math.asin(max(-1.0, min(1.0, -R[2, 0])))
    roll = math.atan2(R[2, 1], R[2, 2])
    yaw = math.atan2(R[1, 0], R[0, 0])
    return roll, pitch, yaw


def rpy_quat(roll, pitch, yaw):
    cr, sr = math.cos(roll / 2), math.sin(roll / 2)
    cp, sp = math.cos(pitch / 2), math.sin(pitch / 2)
    cy, sy = math.cos(yaw / 2), math.sin(yaw / 2)
    return (sr * cp * cy - cr * sp * sy, cr * sp * cy + sr * cp * sy,
            cr * cp * sy - sr * sp * cy, cr * cp * cy + sr * sp * sy)


def angle_diff(a, b):
    return abs(math.atan2(math.sin(a - b), math.cos(a - b)))


class Evaluator:
    def __init__(self, args, extrinsics):
        self.args = args
        self.lock = threading.Lock()
        self.mounts = {s["name"]: s for s in extrinsics["sensors"]}
        v = self.mounts[args.vertical_sensor]
        self.vertical_R = quat_matrix(*v["quaternion_xyzw"])
        self.vertical_t = np.array(v["xyz"], dtype=float)
        # Pending messages by stamp, until their partner arrives.
        self.classified, self.truth = {}, {}
        self.scans, self.scan_truth, self.fits = {}, {}, {}
        self.acc = dict(scans=0, points=0, truth_ground=0, truth_obstacle=0, labelled_ground=0,
                        ground_as_ground=0, obstacle_as_obstacle=0)
        self.fit_abs_errors = []   # per true-ground return of a fitted scan [m]
        self.fit_scans = 0
        self.fit_valid = 0
        self.diagnostics = {}
        self.last_clock = None
        self.last_clock_wall = time.time()
        self.first_stamp = None
        self.screenshot_done = args.screenshot_cmd == ""

    # --- VerticalScanGround against the Velodyne truth ---
    def on_classified(self, msg):
        self._pair(self.classified, self.truth, msg.header.stamp, msg, self._score_cloud, True)

    def on_truth(self, msg):
        self._pair(self.truth, self.classified, msg.header.stamp, msg, self._score_cloud, False)

    def _pair(self, mine, other, stamp, msg, score, mine_is_first):
        key = stamp.to_nsec()
        with self.lock:
            if key in other:
                partner = other.pop(key)
                pair = (msg, partner) if mine_is_first else (partner, msg)
            else:
                mine[key] = msg
                while len(mine) > 50:
                    mine.pop(min(mine))
                return
        try:
            score(*pair)
        except Exception as e:  # a bad message must not stop the evaluation
            rospy.logerr_throttle(5, "demo_evaluate: %s" % e)

    def _score_cloud(self, classified, truth):
        labels = field_column(classified, "label", np.uint8)
        classes = field_column(truth, "class", np.uint8)
        if labels.size != classes.size:
            rospy.logwarn_throttle(5, "classified has %d points, truth %d: skipped" % (labels.size, classes.size))
            return
        g = np.isin(classes, GROUND_CLASSES)
        o = np.isin(classes, OBSTACLE_CLASSES)
        lg = labels == LABEL_GROUND
        lo = labels == LABEL_OBSTACLE
        with self.lock:
            a = self.acc
            a["scans"] += 1
            a["points"] += int(labels.size)
            a["truth_ground"] += int(g.sum())
            a["truth_obstacle"] += int(o.sum())
            a["labelled_ground"] += int(lg.sum())
            a["ground_as_ground"] += int((g & lg).sum())
            a["obstacle_as_obstacle"] += int((o & lo).sum())

    # --- HoughGround against the vertical scanner's truth ---
    def on_scan(self, msg):
        self._triple(self.scans, msg)

    def on_scan_truth(self, msg):
        self._triple(self.scan_truth, msg)

    def on_fit(self, msg):
        self._triple(self.fits, msg)

    def _triple(self, store, msg):
        key = msg.header.stamp.to_nsec()
        with self.lock:
            store[key] = msg
            if not (key in self.scans and key in self.scan_truth and key in self.fits):
                for s in (self.scans, self.scan_truth, self.fits):
                    while len(s) > 400:
                        s.pop(min(s))
                return
            scan, truth, fit = self.scans.pop(key), self.scan_truth.pop(key), self.fits.pop(key)
        try:
            self._score_fit(scan, truth, fit)
        except Exception as e:
            rospy.logerr_throttle(5, "demo_evaluate: %s" % e)

    def _score_fit(self, scan, truth, fit):
        with self.lock:
            self.fit_scans += 1
        if not fit.valid:
            return
        ranges = np.asarray(scan.ranges, dtype=float)
        classes = field_column(truth, "class", np.uint8)
        if classes.size != ranges.size:
            return
        angles = scan.angle_min + scan.angle_increment * np.arange(ranges.size)
        ok = np.isfinite(ranges) & (ranges >= scan.range_min) & (ranges <= scan.range_max) & \
            np.isin(classes, GROUND_CLASSES)
        if not ok.any():
            return
        r, a = ranges[ok], angles[ok]
        pts = np.stack([r * np.cos(a), r * np.sin(a), np.zeros_like(r)], axis=1)
        ground_pts = pts @ self.vertical_R.T + self.vertical_t   # in base_link (on the ground)
        d = np.array([fit.direction.x, fit.direction.y])
        rel = ground_pts[:, :2] - self.vertical_t[:2]
        along = rel @ d if fit.signed_r else np.linalg.norm(rel, axis=1)
        within = (along >= fit.r_min) & (along <= fit.r_max)
        err = np.abs(ground_pts[:, 2] - (fit.ground + fit.slope * along))[within]
        with self.lock:
            self.fit_valid += 1
            self.fit_abs_errors.extend(err.tolist())

    # --- Processing times ---
    def on_diagnostics(self, msg):
        for st in msg.status:
            values = {kv.key: kv.value for kv in st.values}
            if "processing time mean [ms]" in values:
                with self.lock:
                    self.diagnostics[st.name] = values

    def on_clock(self, msg):
        with self.lock:
            if self.first_stamp is None:
                self.first_stamp = msg.clock.to_sec()
            self.last_clock = msg.clock.to_sec()
            self.last_clock_wall = time.time()
            shoot = (not self.screenshot_done and
                     self.last_clock - self.first_stamp >= self.args.screenshot_at)
            if shoot:
                self.screenshot_done = True
        if shoot:
            rc = subprocess.call(self.args.screenshot_cmd, shell=True)
            if rc != 0:
                rospy.logerr("demo_evaluate: screenshot command failed (%d)" % rc)

    # --- Calibration ---
    def calibrate(self):
        t = self.mounts[self.args.calibrate_sensor]
        true_xyz = np.array(t["xyz"], dtype=float)
        true_rpy = np.array(t["rpy"], dtype=float)
        off = np.array(self.args.guess_offset, dtype=float)
        guess_xyz, guess_rpy = true_xyz + off[:3], true_rpy + off[3:]
        req = CalibrateRequest()
        req.method = self.args.calibration_method
        req.initial_guess = Transform()
        req.initial_guess.translation.x, req.initial_guess.translation.y, req.initial_guess.translation.z = guess_xyz
        q = rpy_quat(*guess_rpy)
        (req.initial_guess.rotation.x, req.initial_guess.rotation.y,
         req.initial_guess.rotation.z, req.initial_guess.rotation.w) = q
        req.spread = list(self.args.spread)
        rospy.wait_for_service(self.args.calibrate_service, timeout=20)
        call = rospy.ServiceProxy(self.args.calibrate_service, Calibrate)
        wall = time.time()
        res = call(req)
        wall = time.time() - wall
        tr = res.transform.transform
        est_xyz = np.array([tr.translation.x, tr.translation.y, tr.translation.z])
        est_rpy = rpy_of(quat_matrix(tr.rotation.x, tr.rotation.y, tr.rotation.z, tr.rotation.w))
        errors = {n: float(abs(est_xyz[i] - true_xyz[i])) for i, n in enumerate("xyz")}
        for i, n in enumerate(("roll", "pitch", "yaw")):
            errors[n] = float(angle_diff(est_rpy[i], true_rpy[i]))
        guess_err = {n: float(abs(off[i])) for i, n in enumerate(("x", "y", "z", "roll", "pitch", "yaw"))}
        return dict(success=bool(res.success), message=res.message, method=req.method or "default",
                    target=self.args.calibrate_sensor, errors=errors, initial_errors=guess_err,
                    unobservable=list(res.unobservable), elapsed=float(res.elapsed),
                    call_seconds=wall, launch_line=res.launch_line)

    def summary(self):
        a = self.acc
        ratio = lambda x, y: (float(x) / y) if y else float("nan")
        errs = np.array(self.fit_abs_errors) if self.fit_abs_errors else np.array([float("nan")])
        times = {}
        for name, v in self.diagnostics.items():
            times[name] = dict(mean_ms=float(v["processing time mean [ms]"]),
                               max_ms=float(v.get("processing time max [ms]", "nan")))
        return dict(
            vertical_scan=dict(scans=a["scans"], points=a["points"],
                               ground_precision=ratio(a["ground_as_ground"], a["labelled_ground"]),
                               ground_recall=ratio(a["ground_as_ground"], a["truth_ground"]),
                               obstacle_recall=ratio(a["obstacle_as_obstacle"], a["truth_obstacle"])),
            hough=dict(scans=self.fit_scans, valid_fits=self.fit_valid,
                       ground_returns=len(self.fit_abs_errors),
                       median_abs_error_m=float(np.median(errs)),
                       p95_abs_error_m=float(np.percentile(errs, 95)),
                       rms_error_m=float(np.sqrt(np.mean(errs ** 2)))),
            processing_ms=times)


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--extrinsics", required=True, help="true extrinsics YAML of ladar_simulate")
    p.add_argument("--json", required=True)
    p.add_argument("--vertical-sensor", default="sick_vertical")
    p.add_argument("--calibrate-sensor", default="", help="sensor name; empty: no calibration")
    p.add_argument("--calibrate-service", default="/calibration/calibrate")
    p.add_argument("--calibration-method", default="")
    p.add_argument("--guess-offset", type=float, nargs=6, default=[0.3, -0.2, 0.2, 0.03, -0.03, 0.05],
                   help="initial guess = truth + this (x y z [m] roll pitch yaw [rad])")
    p.add_argument("--spread", type=float, nargs=6, default=[0.5, 0.5, 0.5, 0.1, 0.1, 0.1])
    p.add_argument("--idle", type=float, default=4.0, help="wall seconds without /clock = bag ended")
    p.add_argument("--timeout", type=float, default=300.0)
    p.add_argument("--screenshot-cmd", default="")
    p.add_argument("--screenshot-at", type=float, default=8.0, help="bag seconds")
    args = p.parse_args(rospy.myargv()[1:])
    with open(args.extrinsics) as f:
        extrinsics = yaml.safe_load(f)

    rospy.init_node("demo_evaluate")
    ev = Evaluator(args, extrinsics)
    subs = [
        rospy.Subscriber("/vertical_scan_ground/classified", PointCloud2, ev.on_classified, queue_size=20, buff_size=1 << 26),
        rospy.Subscriber("/velodyne_points_truth", PointCloud2, ev.on_truth, queue_size=20, buff_size=1 << 24),
        rospy.Subscriber("/sick_vertical/scan", LaserScan, ev.on_scan, queue_size=200),
        rospy.Subscriber("/sick_vertical/scan_truth", PointCloud2, ev.on_scan_truth, queue_size=200),
        rospy.Subscriber("/hough_ground/ground_fit", HoughGroundFit, ev.on_fit, queue_size=200),
        rospy.Subscriber("/diagnostics", DiagnosticArray, ev.on_diagnostics, queue_size=20),
        rospy.Subscriber("/clock", Clock, ev.on_clock, queue_size=10),
    ]
    start = time.time()
    # Wait for the bag to start, then for it to end.
    while not rospy.is_shutdown():
        time.sleep(0.2)
        with ev.lock:
            started = ev.last_clock is not None
            idle = time.time() - ev.last_clock_wall
        if started and idle > args.idle:
            break
        if time.time() - start > args.timeout:
            print("demo_evaluate: the bag did not %s within %.0f s" % ("end" if started else "start", args.timeout))
            return 1
    for s in subs:
        s.unregister()
    out = ev.summary()
    if args.calibrate_sensor:
        try:
            out["calibration"] = ev.calibrate()
        except Exception as e:
            print("demo_evaluate: the calibration service failed: %s" % e)
            return 1
    with open(args.json, "w") as f:
        json.dump(out, f, indent=2)
    problems = []
    if out["vertical_scan"]["scans"] == 0:
        problems.append("no /vertical_scan_ground/classified cloud paired with its truth")
    if out["hough"]["valid_fits"] == 0:
        problems.append("no valid /hough_ground/ground_fit paired with its scan and truth")
    if not out["processing_ms"]:
        problems.append("no processing times on /diagnostics")
    if problems:
        print("demo_evaluate: " + "; ".join(problems))
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
