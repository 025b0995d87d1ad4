"""Covariance of every sample of a 10^7-sample differential-drive log.

Runs both engines (numba step recursion, Kelly prefix sums) through
``odomkit.propagate.recursion.iter_track_covariance``, which yields bounded chunks: the
benchmark measures the engine, not the allocation of a 720 MB (10^7, 3, 3) output. The
reference is a plain per-step loop of 3×3 numpy products on a prefix of the log, timed in
the same process; the ratio compares time per sample.

The default recursion turns a carried heading vector instead of calling cos/sin at every
step, which needs headings consistent with the steps (a dead-reckoned track). The line
``recursion-fallback`` times what a caller with other headings gets: the same log with
headings jittered by 1e-9 rad, so the kernel takes a real cos/sin at every step.

    .venv/bin/python benchmarks/propagation.py [--samples 10000000] [--reference 100000]
"""

from __future__ import annotations

import argparse
import time
import tracemalloc

import numpy as np
from scipy.signal import lfilter

from odomkit.integrate import dead_reckon
from odomkit.kinematics import BodySteps, diff_body_steps, step_jacobians
from odomkit.noise import WheelNoise
from odomkit.noise.wheel import wheel_input_cov
from odomkit.propagate.recursion import iter_track_covariance
from odomkit.robot import DiffDrive

RATE_HZ = 100.0
WHEEL_BASE = 0.4
NOISE = WheelNoise(k_left=0.001, k_right=0.0012)


def synthesise(n: int, seed: int = 0) -> tuple[BodySteps, np.ndarray]:
    """Smooth random wheel speeds (AR(1) low-pass of white noise, ~1 s correlation)."""
    rng = np.random.default_rng(seed)
    dt = 1.0 / RATE_HZ
    pole = np.exp(-dt / 1.0)
    speeds = lfilter([1 - pole], [1, -pole], rng.normal(0.0, 3.0, (2, n)), axis=1) + 0.5
    d_left, d_right = speeds[0] * dt, speeds[1] * dt
    dd, dtheta = diff_body_steps(d_left, d_right, WHEEL_BASE)
    steps = BodySteps(dd, dtheta, np.full(n, dt), {"d_left": d_left, "d_right": d_right},
                      DiffDrive(WHEEL_BASE))
    return steps, dead_reckon(dd, dtheta)


def reference_loop(steps: BodySteps, poses: np.ndarray, n: int) -> np.ndarray:
    """Plain recursion: step Jacobians, then one 3×3 numpy product chain per step."""
    d_l, d_r = steps.inputs["d_left"][:n], steps.inputs["d_right"][:n]
    q = wheel_input_cov(d_l, d_r, WHEEL_BASE, NOISE)
    F, G = step_jacobians(poses[:n, 2], steps.dd[:n], steps.dtheta[:n], "exact")
    P = np.zeros((3, 3))
    out = np.empty((n, 3, 3))
    for k in range(n):
        P = F[k] @ P @ F[k].T + G[k] @ q[k] @ G[k].T
        out[k] = P
    return out


def engine_options(engine: str) -> dict:
    """Keyword arguments of iter_track_covariance for "recursion", "recursion-parallel",
    "recursion-fallback" (same engine as "recursion", other poses) or "transition"."""
    return {"engine": engine.split("-")[0], "parallel": engine.endswith("-parallel")}


def run_engine(steps: BodySteps, poses: np.ndarray, engine: str) -> np.ndarray:
    """Consume the chunks of one engine; returns the last covariance."""
    last = None
    for _, chunk in iter_track_covariance(steps, poses, NOISE, np.zeros((3, 3)),
                                          **engine_options(engine)):
        last = chunk[-1]
    assert last is not None
    return last


def jittered(poses: np.ndarray, seed: int = 1) -> np.ndarray:
    """The poses with headings moved by ~1e-9 rad: no longer θ_0 + ΣΔθ (in place)."""
    poses[:, 2] += np.random.default_rng(seed).normal(0.0, 1e-9, poses.shape[0])
    return poses


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=10_000_000)
    parser.add_argument("--reference", type=int, default=100_000)
    args = parser.parse_args()

    t0 = time.perf_counter()
    steps, poses = synthesise(args.samples)
    print(f"synthesised {args.samples:,} steps at {RATE_HZ:.0f} Hz "
          f"({np.abs(steps.dd).sum() / 1000:.1f} km) in {time.perf_counter() - t0:.1f} s")

    t0 = time.perf_counter()
    ref = reference_loop(steps, poses, args.reference)
    t_ref = (time.perf_counter() - t0) / args.reference
    print(f"reference numpy loop: {1 / t_ref:,.0f} samples/s (on {args.reference:,} steps)")

    # Warm-up: numba compilation (cached on disk after the first run) is not the engine.
    small = BodySteps(steps.dd[:1000], steps.dtheta[:1000], steps.dt[:1000],
                      {k: v[:1000] for k, v in steps.inputs.items()}, steps.robot)
    for engine in ("recursion", "recursion-parallel", "transition", "recursion-fallback"):
        if engine == "recursion-fallback":
            poses = jittered(poses)
            ref = reference_loop(steps, poses, args.reference)
        run_engine(small, poses[:1001], engine)
        chunk = next(c for r, c in iter_track_covariance(
            steps, poses, NOISE, np.zeros((3, 3)), chunk_size=args.reference,
            **engine_options(engine)) if r > 0)
        # Largest difference relative to the largest entry of the same matrix.
        rel = np.max(np.abs(chunk - ref).max(axis=(1, 2)) / np.abs(ref).max(axis=(1, 2)))
        t0 = time.perf_counter()
        final = run_engine(steps, poses, engine)
        seconds = time.perf_counter() - t0
        tracemalloc.start()
        run_engine(steps, poses, engine)
        _, peak = tracemalloc.get_traced_memory()
        tracemalloc.stop()
        ratio = t_ref * args.samples / seconds
        print(f"{engine:>18}: {args.samples:,} covariances in {seconds:.2f} s = "
              f"{args.samples / seconds:,.0f} samples/s, ratio {ratio:,.0f}"
              f" x the loop, peak extra memory {peak / 2**20:.0f} MiB, "
              f"max rel diff vs loop on prefix {rel:.1e}, "
              f"final sigma_x {np.sqrt(final[0, 0]):.3f} m")


if __name__ == "__main__":
    main()
