"""Closed-form prediction against the step recursion it replaces.

Chong–Kleeman's point: a closed form per segment instead of propagating the covariance
over many small steps. This times ``odomkit.propagate.predict.predict`` (closed) on
Table 1's arc and on a 4-segment path against a plain per-step loop of 3×3 numpy products
over the paper's 10 000 partitions per segment, run in the same process, and prints the
ratio and the relative difference of the covariances.

    .venv/bin/python benchmarks/predict_closed.py [--partitions 10000] [--repeat 200]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from odomkit.kinematics import step_jacobians
from odomkit.noise import WheelNoise
from odomkit.path import Arc, Spin, Straight
from odomkit.propagate.predict import discretise_path, predict

NOISE = WheelNoise(0.003, 0.002)
PATHS = {"table 1 arc": [Arc(3.0, 1.0)],
         "4 segments": [Arc(3.0, 1.0), Straight(2.0), Spin(1.5708), Arc(-1.0, 2.0)]}


def reference(segments, partitions: int) -> np.ndarray:
    poses, dd, dth, q = discretise_path(segments, NOISE, 0.4, partitions)
    F, G = step_jacobians(poses[:-1, 2], dd, dth, "exact")
    P = np.zeros((3, 3))
    for k in range(dd.size):
        P = F[k] @ P @ F[k].T + G[k] @ q[k] @ G[k].T
    return P


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--partitions", type=int, default=10_000)
    parser.add_argument("--repeat", type=int, default=200)
    args = parser.parse_args()
    for name, segs in PATHS.items():
        t0 = time.perf_counter()
        for _ in range(args.repeat):
            closed = predict(segs, NOISE, 0.4).cov
        t_closed = (time.perf_counter() - t0) / args.repeat
        t0 = time.perf_counter()
        ref = reference(segs, args.partitions)
        t_ref = time.perf_counter() - t0
        diff = np.max(np.abs(ref - closed)) / np.max(np.abs(closed))
        print(f"{name:12s}: closed {t_closed * 1e3:7.3f} ms, reference loop "
              f"({args.partitions} steps/segment) {t_ref * 1e3:8.1f} ms, "
              f"ratio {t_ref / t_closed:8.0f}x, relative difference {diff:.1e}")


if __name__ == "__main__":
    main()
