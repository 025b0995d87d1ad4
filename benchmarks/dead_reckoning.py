"""Dead-reckoning throughput: vectorised odomkit vs a plain per-sample Python loop.

Run: ``python benchmarks/dead_reckoning.py [--samples 10000000]``. Prints samples per
second for both and their ratio (target: 100 or more). The plain loop runs on a prefix
of the same log (it would take minutes on all of it); both rates are per sample.
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

from odomkit.integrate import dead_reckon
from odomkit.kinematics import diff_body_steps


def plain_loop(d_left, d_right, wheel_base, pose0):
    """The textbook implementation: one exact-arc step per sample, in Python."""
    x, y, th = pose0
    out = [(x, y, th)]
    for dl, dr in zip(d_left, d_right, strict=True):
        dd = 0.5 * (dr + dl)
        dth = (dr - dl) / wheel_base
        half = 0.5 * dth
        chord = dd * (math.sin(half) / half if half != 0.0 else 1.0)
        x += chord * math.cos(th + half)
        y += chord * math.sin(th + half)
        th += dth
        out.append((x, y, th))
    return np.array(out)


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--samples", type=int, default=10_000_000)
    parser.add_argument("--loop-samples", type=int, default=200_000)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    rng = np.random.default_rng(0)
    n = args.samples
    # Smoothly varying wheel speeds at 100 Hz, as from a real robot, with reversals.
    t = np.arange(n) * 0.01
    d_left = 0.004 * np.sin(0.05 * t) + 0.0005 * rng.standard_normal(n)
    d_right = 0.004 * np.sin(0.05 * t + 0.3) + 0.0005 * rng.standard_normal(n)
    wheel_base = 0.3

    # Compile the numba kernel (cached on disk after the first run) outside the timing.
    dead_reckon(np.zeros(30_000), np.zeros(30_000))
    # Best of a few repeats for both, as timeit does: the minimum is the least disturbed
    # by other processes on a shared machine.
    fast = slow = float("inf")
    m = min(args.loop_samples, n)
    for _ in range(args.repeat):
        start = time.perf_counter()
        dd, dth = diff_body_steps(d_left, d_right, wheel_base)
        poses = dead_reckon(dd, dth, (0.0, 0.0, 0.0), "exact")
        fast = min(fast, time.perf_counter() - start)
        del dd, dth
        start = time.perf_counter()
        ref = plain_loop(d_left[:m].tolist(), d_right[:m].tolist(), wheel_base, (0.0, 0.0, 0.0))
        slow = min(slow, time.perf_counter() - start)
    agree = np.max(np.abs(poses[: m + 1] - ref))

    fast_rate, slow_rate = n / fast, m / slow
    print(f"odomkit exact dead reckoning: {n:,} samples in {fast:.3f} s = {fast_rate:,.0f} samples/s")
    print(f"plain Python loop:            {m:,} samples in {slow:.3f} s = {slow_rate:,.0f} samples/s")
    print(f"max |difference| on the common prefix: {agree:.2e}")
    print(f"ratio: {fast_rate / slow_rate:.0f}x (target >= 100)")


if __name__ == "__main__":
    main()
