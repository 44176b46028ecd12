#!/usr/bin/python3
"""Prints scripts/demo's summary table from demo_evaluate.py's JSON and calibration_benchmark's
JSON. Exits non-zero when a figure the table needs is missing."""
import argparse
import json
import math
import sys


def num(v, fmt="%.3f"):
    return "n/a" if v is None or (isinstance(v, float) and math.isnan(v)) else fmt % v


def main():
    p = argparse.ArgumentParser()
    p.add_argument("summary")
    p.add_argument("benchmark")
    p.add_argument("--run-seconds", type=float, default=float("nan"))
    p.add_argument("--noise", default="datasheet")
    a = p.parse_args()
    with open(a.summary) as f:
        s = json.load(f)
    with open(a.benchmark) as f:
        b = json.load(f)

    rows = []
    v = s["vertical_scan"]
    rows.append(("VerticalScanGround (Velodyne, %d revolutions)" % v["scans"], ""))
    rows.append(("  ground precision", num(v["ground_precision"])))
    rows.append(("  ground recall", num(v["ground_recall"])))
    rows.append(("  obstacle recall", num(v["obstacle_recall"])))
    h = s["hough"]
    rows.append(("HoughGround (vertical SICK, %d/%d scans fitted)" % (h["valid_fits"], h["scans"]), ""))
    rows.append(("  fit error, true ground returns: median", num(h["median_abs_error_m"]) + " m"))
    rows.append(("  fit error: 95th percentile / RMS", "%s / %s m" % (num(h["p95_abs_error_m"]), num(h["rms_error_m"]))))
    c = s.get("calibration")
    if c:
        e, g = c["errors"], c["initial_errors"]
        rows.append(("Calibration service: %s against velodyne (%s)" % (c["target"], c["method"]), ""))
        rows.append(("  result", ("success" if c["success"] else "NOT a success") +
                     ("; unobservable: " + " ".join(c["unobservable"]) if c["unobservable"] else "")))
        rows.append(("  initial guess error x y z [m]", " ".join(num(g[k]) for k in "xyz")))
        rows.append(("  error x y z [m]", " ".join(num(e[k]) for k in "xyz")))
        rows.append(("  initial guess error roll pitch yaw [rad]", " ".join(num(g[k], "%.4f") for k in ("roll", "pitch", "yaw"))))
        rows.append(("  error roll pitch yaw [rad]", " ".join(num(e[k], "%.4f") for k in ("roll", "pitch", "yaw"))))
        rows.append(("  time (calibration / service call)", "%s / %s s" % (num(c["elapsed"], "%.1f"), num(c["call_seconds"], "%.1f"))))
    be = b["errors"]
    rows.append(("Calibration experiment (%s, %s world, %s)" % (b["pair"], b["world"], b["method"]), ""))
    rows.append(("  error x y z [m]", " ".join(num(be[k]["worst"]) for k in "xyz")))
    rows.append(("  error roll pitch yaw [rad]", " ".join(num(be[k]["worst"], "%.4f") for k in ("roll", "pitch", "yaw"))))
    rows.append(("  time per trial (wall)", num(b["seconds_per_trial"]["median"], "%.1f") + " s" +
                 ("; unobservable: " + " ".join(b["unobservable"]) if b.get("unobservable") else "")))
    rows.append(("Processing time per scan (mean / max)", ""))
    for name in sorted(s["processing_ms"]):
        t = s["processing_ms"][name]
        rows.append(("  " + name.split(": ", 1)[-1], "%s / %s ms" % (num(t["mean_ms"], "%.2f"), num(t["max_ms"], "%.2f"))))
    rows.append(("Demo run (simulate, play, evaluate, calibrate)", num(a.run_seconds, "%.0f") + " s"))

    w = max(len(r[0]) for r in rows) + 2
    line = "-" * (w + 28)
    noise = {"datasheet": "datasheet range noise (HDL-64E 2 cm, as on the road)",
             "table4.1": "the thesis's Table 4.1 noise (Velodyne 0.2 m): a stress case, not the road",
             "none": "no range noise"}.get(a.noise, a.noise + " noise")
    print(line)
    print("ladar_perception demo: the urban world against the simulator's truth")
    print("at " + noise)
    print(line)
    for name, value in rows:
        print(name.ljust(w) + value)
    print(line)
    print("On real HDL-64E scans (SemanticKITTI, labelled): see doc/benchmarks.md")
    print(line)
    missing = v["scans"] == 0 or h["valid_fits"] == 0 or not s["processing_ms"]
    return 1 if missing else 0


if __name__ == "__main__":
    sys.exit(main())
