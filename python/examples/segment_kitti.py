#!/usr/bin/env python3
"""Segments a KITTI .bin scan with ladar_perception and saves a top-down PNG; with a
SemanticKITTI .label, prints precision, recall and F1 of the ground (ground_eval's protocols).

    python3 python/examples/segment_kitti.py SCAN.bin [--label SCAN.label] [--png top.png]
        [--method NAME] [--sensor-height 1.73] [--errors errors.png] [--repeat N]
"""
import argparse
import sys
import time

import numpy as np

import ladar_perception as lp


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scan", help="KITTI .bin (float32 x, y, z, intensity)")
    ap.add_argument("--label", help="SemanticKITTI .label of the scan: print P/R/F1")
    ap.add_argument("--png", default="segment_kitti.png", help="top-down picture (default %(default)s)")
    ap.add_argument("--errors", help="with --label: picture of the errors (ground_eval's colours)")
    ap.add_argument("--method", default="vertical_scan", choices=lp.ground_model_names())
    ap.add_argument("--sensor-height", type=float, default=1.73, help="[m] (KITTI: 1.73)")
    ap.add_argument("--repeat", type=int, default=0, help="time N calls, print the median")
    args = ap.parse_args()

    points = lp.read_kitti_bin(args.scan)  # (N, 4) float32, viewed in place by segment()
    model = lp.GroundModel(args.method, sensor_height=args.sensor_height)
    labels, p_obstacle = model.segment(points)
    print("%s: %d points, %s: ground %d, obstacle %d, unknown %d" % (
        args.scan, len(points), model.name, np.sum(labels == lp.LABEL_GROUND),
        np.sum(labels == lp.LABEL_OBSTACLE), np.sum(labels == lp.LABEL_UNKNOWN)))
    if args.repeat > 0:
        ms = []
        for _ in range(args.repeat):
            t0 = time.perf_counter()
            model.segment(points)
            ms.append(1e3 * (time.perf_counter() - t0))
        print("median_ms=%.3f min_ms=%.3f" % (np.median(ms), min(ms)))
    if args.label:
        classes = lp.read_semantic_kitti_label(args.label, len(points))
        for protocol in ("A", "B"):
            s = lp.score_ground(points, classes, labels, args.sensor_height, protocol)
            print("protocol %s: P %.4f  R %.4f  F1 %.4f  obstacle recall %.4f" % (
                protocol, s["precision"], s["recall"], s["f1"], s["obstacle_recall"]))
        if args.errors:
            lp.write_outcome_png(args.errors, points, classes, labels, args.sensor_height)
    lp.write_top_down_png(args.png, points, labels)
    print("wrote", args.png)
    return 0


if __name__ == "__main__":
    sys.exit(main())
