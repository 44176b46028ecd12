"""ladar_perception from Python: the package's ROS-free core on NumPy arrays.

    import numpy as np
    import ladar_perception as lp

    points = lp.read_kitti_bin("000000.bin")             # (N, 4) float32
    labels, p_obstacle = lp.VerticalScanGround().segment(points)
    # labels: uint8 LABEL_GROUND 0, LABEL_OBSTACLE 1, LABEL_UNKNOWN 2; p_obstacle: float32

Ground models: GroundModel(name) for every name of ground_model_names(), VerticalScanGround(params)
with VerticalScanParams (the core's parameter table). The simulator: World(name), VelodyneModel,
simulate_scan(). The scorer of ground_eval --semantickitti: score_ground(). Pictures:
write_top_down_png(), write_outcome_png(), write_png().
"""
import numpy as _np

from ._core import (  # noqa: F401
    LABEL_GROUND, LABEL_OBSTACLE, LABEL_UNKNOWN, GroundModel, VelodyneModel, VerticalScanGround,
    VerticalScanParams, World, ground_model_names, hdl64e_elevations_deg, lidar_models, read_kitti_bin,
    read_semantic_kitti_label, score_ground, semantic_kitti_class_name, semantic_kitti_is_ground,
    surface_classes, world_names, write_outcome_png, write_png)
from . import _core

# The simulator's truth classes as SemanticKITTI classes, so that score_ground() scores simulated
# scans: road 40, sidewalk 48, terrain 72 (ground); curb face 52 other-structure, car 10,
# wall 50 building, pole 80, person 30, pothole 99 other-object (non-ground: the simulator's
# truth calls a curb's face and a hole obstacles).
SIM_TO_SEMANTIC_KITTI = _np.array([40, 48, 72, 52, 10, 50, 80, 30, 99], dtype=_np.uint16)


def sim_truth_to_semantic_kitti(truth):
    """SemanticKITTI classes (uint16) of a simulated scan's truth (World.scan's third array)."""
    truth = _np.asarray(truth)
    if truth.ndim != 1 or truth.dtype.kind not in "iu":
        raise ValueError("truth must be a 1-D integer array (World.scan's truth)")
    if truth.size and (truth.min() < 0 or truth.max() >= len(SIM_TO_SEMANTIC_KITTI)):
        raise ValueError("truth holds a code that is not a surface class (see surface_classes())")
    return SIM_TO_SEMANTIC_KITTI[truth]


def simulate_scan(world, pose, model=None, seed=0, world_seed=1):
    """One simulated revolution: (points (N, 4) float32, ring (N,) uint16, truth (N,) uint8).

    world: a World or a name of world_names(); pose: the sensor's 4x4 pose in the world, or a time
    [s] on the world's standard drive (sensor 1.73 m above base_link, level); model: a
    VelodyneModel (default: the HDL-64E with its datasheet noise).
    """
    if isinstance(world, str):
        world = World(world, world_seed)
    return world.scan(pose, model, seed)


def top_down_image(points, labels, half_width=40.0, size=1000):
    """(size, size, 3) uint8 top-down picture, x forward up: ground green, obstacle red, unknown
    grey (the colours of ground_segment --png)."""
    pts = _np.asarray(points)
    labels = _np.asarray(labels)
    if pts.ndim != 2 or pts.shape[1] < 3 or labels.shape != (pts.shape[0],):
        raise ValueError("points (N, 3|4) and labels (N,) expected")
    img = _np.empty((size, size, 3), _np.uint8)
    img[:] = (18, 18, 24)
    px_per_m = size / (2.0 * half_width)
    with _np.errstate(invalid="ignore"):
        u = _np.floor(size / 2 - pts[:, 1] * px_per_m)
        v = _np.floor(size / 2 - pts[:, 0] * px_per_m)
        ok = _np.isfinite(u) & _np.isfinite(v) & (u >= 0) & (u < size) & (v >= 0) & (v < size)
    colours = {LABEL_UNKNOWN: (110, 110, 110), LABEL_GROUND: (40, 200, 70),
               LABEL_OBSTACLE: (255, 50, 40)}
    for label in (LABEL_UNKNOWN, LABEL_GROUND, LABEL_OBSTACLE):  # obstacles drawn last
        sel = ok & (labels == label)
        img[v[sel].astype(int), u[sel].astype(int)] = colours[label]
    c = size // 2
    img[c, c - 3:c + 4] = img[c - 3:c + 4, c] = (255, 255, 255)  # the sensor
    return img


def write_top_down_png(path, points, labels, half_width=40.0, size=1000):
    """Writes top_down_image() with the core's PNG writer."""
    write_png(path, top_down_image(points, labels, half_width, size))


__version__ = "0.1.0"
__all__ = [n for n in dir() if not n.startswith("_")]
