"""Monte Carlo engine against a plain vectorised-numpy reference, Chong–Kleeman Table 1.

The experiment of Chong–Kleeman section 6.1: arc L = 3 m, R = 1 m, wheel base 0.4 m,
k = 0.001 m^½, 10⁴ runs × 10⁴ partitions (10⁸ partition steps, 2×10⁸ normals). The
reference is the obvious numpy code (all partitions of a set of runs at once, exact arc
via odomkit.kinematics.step_displacement), timed in the same process on a slice of the
runs; the ratio compares partition steps per second. Then all six settings of Tables 1–2
at full size.

    .venv/bin/python benchmarks/montecarlo.py [--runs 10000] [--partitions 10000]
        [--reference-runs 200] [--workers 2] [--skip-six]
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np

from odomkit.kinematics import step_displacement
from odomkit.noise import WheelNoise
from odomkit.path import Arc
from odomkit.simulate import simulate_runs

B = 0.4
SETTINGS = [((3.0, 1.0), (0.001, 0.001)), ((3.0, 1.0), (0.003, 0.002)),
            ((3.0, 1.0), (0.01, 0.02)), ((15.0, 10.0), (0.001, 0.001)),
            ((15.0, 10.0), (0.003, 0.002)), ((15.0, 10.0), (0.01, 0.02))]


def reference(runs: int, partitions: int, left: float, right: float, k_left: float,
              k_right: float, seed: int = 0) -> np.ndarray:
    """Plain vectorised numpy: draw every partition's wheel noise, integrate at once."""
    rng = np.random.Generator(np.random.SFC64(seed))
    z = rng.standard_normal((2, partitions, runs))
    dl = left / partitions + k_left * np.sqrt(abs(left) / partitions) * z[0]
    dr = right / partitions + k_right * np.sqrt(abs(right) / partitions) * z[1]
    dd, dth = 0.5 * (dl + dr), (dr - dl) / B
    theta = np.cumsum(dth, axis=0) - dth  # heading at the start of each partition
    dx, dy = step_displacement(theta, dd, dth, "exact")
    return np.stack([dx.sum(axis=0), dy.sum(axis=0), theta[-1] + dth[-1]], axis=1)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=10_000)
    parser.add_argument("--partitions", type=int, default=10_000)
    parser.add_argument("--reference-runs", type=int, default=200)
    parser.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    parser.add_argument("--skip-six", action="store_true")
    args = parser.parse_args()
    path, (kl, kr) = [Arc(*SETTINGS[0][0])], SETTINGS[0][1]

    # compile the numba kernel outside the timing
    simulate_runs(path, WheelNoise(kl, kr), B, runs=4, partitions=10, seed=0)

    steps = args.runs * args.partitions
    t0 = time.perf_counter()
    mc = simulate_runs(path, WheelNoise(kl, kr), B, runs=args.runs, partitions=args.partitions,
                       seed=1, workers=args.workers)
    t_engine = time.perf_counter() - t0

    ref_steps = args.reference_runs * args.partitions
    t0 = time.perf_counter()
    ref = reference(args.reference_runs, args.partitions, 3.0, 1.0, kl, kr)
    t_ref = time.perf_counter() - t0

    rate_engine, rate_ref = steps / t_engine, ref_steps / t_ref
    print(f"Table 1 path, {args.runs} runs x {args.partitions} partitions = {steps:.3g} steps, "
          f"{args.workers} workers, engine {mc.engine}")
    print(f"  odomkit.simulate : {t_engine:8.3f} s  {rate_engine:10.3g} steps/s")
    print(f"  numpy reference  : {t_ref:8.3f} s  {rate_ref:10.3g} steps/s "
          f"({args.reference_runs} runs)")
    print(f"  speed-up (steps/s ratio): {rate_engine / rate_ref:.1f}x")
    print(f"  std check, engine vs reference slice: {np.std(mc.final, axis=0)} vs "
          f"{np.std(ref, axis=0)}")
    if args.skip_six:
        return
    t0 = time.perf_counter()
    for (left, right), (k_left, k_right) in SETTINGS:
        t1 = time.perf_counter()
        simulate_runs([Arc(left, right)], WheelNoise(k_left, k_right), B, runs=args.runs,
                      partitions=args.partitions, seed=2, workers=args.workers)
        print(f"  arc {left:g},{right:g}  k = {k_left:g},{k_right:g}: "
              f"{time.perf_counter() - t1:6.2f} s")
    print(f"all six Table 1-2 settings: {time.perf_counter() - t0:.2f} s")


if __name__ == "__main__":
    main()
