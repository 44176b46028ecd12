#!/usr/bin/env python3
"""The Python call against the C++ tool on one scan: ground_segment SCAN --repeat N prints the
median of N core calls; here the same scan, model and N through VerticalScanGround.segment()
(the whole Python call: argument checks, the view, the NaN check, the core call, the NumPy
results). Rounds alternate the two back to back; prints each round and the medians.

    source build/devel/setup.bash
    /usr/bin/python3 scripts/python_bench.py SCAN.bin [--repeat 200] [--rounds 5] [--method NAME]
"""
import argparse
import os
import re
import statistics
import subprocess
import sys
import time

import numpy as np

import ladar_perception as lp


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scan")
    ap.add_argument("--repeat", type=int, default=200)
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--method", default="vertical_scan")
    ap.add_argument("--tool", default=os.path.join(os.environ.get("LADAR_BUILD", "build"), "devel", "lib",
                                                   "ladar_perception", "ground_segment"))
    args = ap.parse_args()

    points = lp.read_kitti_bin(args.scan)
    model = lp.GroundModel(args.method)
    labels, _ = model.segment(points)  # warms the workspace, as the tool does
    cpp, py = [], []
    for r in range(args.rounds):
        out = subprocess.run([args.tool, args.scan, "--method", args.method, "--repeat", str(args.repeat)],
                             check=True, capture_output=True, text=True).stdout
        cpp.append(float(re.search(r"median_ms=([0-9.]+)", out).group(1)))
        ms = []
        for _ in range(args.repeat):
            t0 = time.perf_counter()
            model.segment(points)
            ms.append(1e3 * (time.perf_counter() - t0))
        py.append(statistics.median(ms))
        print("round %d: C++ median_ms=%.3f  Python median_ms=%.3f" % (r + 1, cpp[-1], py[-1]))
    c, p = statistics.median(cpp), statistics.median(py)
    print("%s, %d points, %s, %d rounds of %d calls: C++ %.3f ms, Python %.3f ms, Python/C++ %.3f"
          % (os.path.basename(args.scan), len(points), model.name, args.rounds, args.repeat, c, p, p / c))
    return 0


if __name__ == "__main__":
    sys.exit(main())
