"""Peer of `cargo xtask bench metrics`: the density-aware Chamfer distance of two point sets with
pykdtree, as the reference code computes it.

Input (from xtask): `first.npy` and `second.npy` (n × 2 float64, our DCD case's point sets),
`input.json` with `repeats`. Timed (one untimed run first, then the median of `repeats`): a
kd-tree on each set, the nearest neighbour in the other set of every point, and the formula:
for each point z, C(z) = 1 − exp(−‖z − ẑ‖) / n_ẑ with ẑ its nearest neighbour and n_ẑ the number
of points sharing it; the DCD is the mean of the two directions' mean C.
"""

import amber_peer  # first: the thread settings must precede numpy

import numpy as np
from pykdtree.kdtree import KDTree

case = amber_peer.Case()
first = case.array("first")
second = case.array("second")


def one_direction(queries, targets):
    distances, nearest = KDTree(targets).query(queries, k=1)
    hits = np.bincount(nearest, minlength=len(targets))
    return np.mean(1.0 - np.exp(-distances) / hits[nearest])


def dcd():
    return 0.5 * (one_direction(first, second) + one_direction(second, first))


seconds, seconds_all, cpu_seconds, value = amber_peer.timed(dcd, case.input["repeats"], warmup=1)
case.finish(
    {
        "library": "pykdtree",
        "points": [len(first), len(second)],
        "seconds": seconds,
        "seconds_all": seconds_all,
        "cpu_seconds": cpu_seconds,
        "dcd": float(value),
    },
    ["pykdtree", "numpy"],
)
