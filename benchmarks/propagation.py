"""Covariance of every sample of a 10^7-sample differential-drive log (``odomkit track``).

Prints, each the minimum over ``--repeat`` runs (the least disturbed by other processes
on a shared machine):

* odomkit: :func:`~odomkit.propagate.recursion.track_covariance` with per-wheel noise,
  into a preallocated (N, 3, 3) output (``out=``), into a fresh one (720 MB the operating
  system must also map), and :func:`~odomkit.propagate.recursion.iter_track_covariance`
  consumed chunk by chunk (bounded memory: no (N, 3, 3) array at all);
* the fastest plain-Python loop of the same recursion (floats from lists, ``math.sin``,
  ``math.cos``; Chong–Kleeman eq. 2 with the exact-arc Jacobians), on a prefix of the log;
  ratios are per sample;
* the copy floor: reading the inputs (θ from the poses, Δd, Δθ, the two wheel travels)
  and writing six covariance columns once, as ``np.copyto`` of those bytes into the
  output's memory; no propagation can beat it.
* ``--stages``: the kernel's stages (:mod:`odomkit.propagate._numba`) timed alone;
  ``--engines``: also the parallel kernel, the transition engine and headings that are
  not a dead-reckoned track's (``recursion-fallback``: a real cos/sin at every step).

Goals (issue 10): at least 100x the loop, within 3x of the floor.

    .venv/bin/python benchmarks/propagation.py [--samples 10000000] [--repeat 5] [--stages] [--engines]
"""

from __future__ import annotations

import argparse
import math
import time
from collections.abc import Callable

import numpy as np
from scipy.signal import lfilter

from odomkit.integrate import dead_reckon
from odomkit.kinematics import BodySteps, diff_body_steps
from odomkit.noise import WheelNoise
from odomkit.propagate.recursion import iter_track_covariance, track_covariance
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


def plain_loop(theta: list[float], dd: list[float], dtheta: list[float], d_left: list[float],
               d_right: list[float], wheel_base: float, k_left: float, k_right: float
               ) -> list[tuple[float, ...]]:
    """P_{k+1} = F P F^T + G Q G^T per step in Python floats: the six entries of P."""
    p00 = p01 = p02 = p11 = p12 = p22 = 0.0
    kl2, kr2, b = k_left * k_left, k_right * k_right, wheel_base
    out = []
    for th, d, a, dl, dr in zip(theta, dd, dtheta, d_left, d_right, strict=True):
        # Cov(d_L, d_R) = diag(k_L²|d_L|, k_R²|d_R|) (Chong–Kleeman eq. 4), mapped to (Δd, Δθ)
        vl, vr = kl2 * abs(dl), kr2 * abs(dr)
        q00, q01, q11 = 0.25 * (vl + vr), 0.5 * (vr - vl) / b, (vl + vr) / (b * b)
        u = 0.5 * a
        if abs(u) > 1e-4:
            f = math.sin(u) / u
            df = 0.5 * (u * math.cos(u) - math.sin(u)) / (u * u)
        else:  # series: the direct formula cancels
            f, df = 1.0 - u * u / 6.0, -u / 6.0
        c, s = math.cos(th + u), math.sin(th + u)
        # exact-arc Jacobians (Chong–Kleeman eq. 16–17 in chord form)
        g00, g10 = f * c, f * s
        g01, g11 = d * (df * c - 0.5 * f * s), d * (df * s + 0.5 * f * c)
        u0, u1 = -d * g10, d * g00
        r00, r01 = g00 * q00 + g01 * q01, g00 * q01 + g01 * q11
        r10, r11 = g10 * q00 + g11 * q01, g10 * q01 + g11 * q11
        p00, p01, p02, p11, p12, p22 = (
            p00 + 2 * u0 * p02 + u0 * u0 * p22 + r00 * g00 + r01 * g01,
            p01 + u0 * p12 + u1 * p02 + u0 * u1 * p22 + r00 * g10 + r01 * g11,
            p02 + u0 * p22 + r01,
            p11 + 2 * u1 * p12 + u1 * u1 * p22 + r10 * g10 + r11 * g11,
            p12 + u1 * p22 + r11,
            p22 + q11)
        out.append((p00, p01, p02, p11, p12, p22))
    return out


def best_of(repeat: int, run: Callable[[], object]) -> float:
    """Minimum wall time of ``repeat`` calls [s]."""
    best = math.inf
    for _ in range(repeat):
        start = time.perf_counter()
        run()
        best = min(best, time.perf_counter() - start)
    return best


def copy_floor(inputs: tuple[np.ndarray, ...], out: np.ndarray, rows: int) -> None:
    """Read every input once and write six float64 columns of ``rows`` rows once: the
    inputs are copied into the output's memory, the rest of those bytes filled."""
    raw = out.reshape(-1).view(np.uint8)
    offset = 0
    for a in inputs:
        np.copyto(raw[offset:offset + a.size * 8].view(np.float64), a)  # θ: a strided view
        offset += a.size * 8
    raw[offset:rows * 48].fill(0)


def stage_times(steps: BodySteps, poses: np.ndarray, out: np.ndarray, repeat: int) -> dict:
    """Each stage of the kernel run alone over the whole log [s] (numba driver)."""
    from numba import njit

    from odomkit.noise.wheel import wheel_cov_coefficients
    from odomkit.propagate import _numba as k

    @njit
    def drive(theta, dd, dtheta, d_left, d_right, wheel, out, stages):  # pragma: no cover
        w = np.zeros(k.WORK)
        t = np.zeros((8, k.CHUNK))
        flat = out.reshape((out.shape[0], 9))
        cov_input = np.empty((0, 2, 2))
        p = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
        for k0 in range(0, theta.size - k.CHUNK + 1, k.CHUNK):
            if stages & 1:
                k._load_blocks(k0, k.CHUNK, theta, dtheta, w)
            if stages & 2:
                k._lane_headings(w, k.METHOD_EXACT)
            if stages & 4:
                k._block_terms(w, t, k.METHOD_EXACT, k.LANES, k0, dd, cov_input, d_left, d_right,
                               wheel, k.QMODE_WHEEL)
            if stages & 8:
                p = k._recur(t, k.CHUNK, k0, p[0], p[1], p[2], p[3], p[4], p[5], out, flat, True)

    names = {1: "load (θ, Δθ into the lanes' buffer)", 2: "headings (SIMD lanes)",
             4: "terms F, G Q G^T (Δd, Q read here)", 8: "recurrence; write (N, 3, 3)"}
    args = (poses[:-1, 2], steps.dd, steps.dtheta, steps.inputs["d_left"], steps.inputs["d_right"],
            wheel_cov_coefficients(WHEEL_BASE, NOISE), out[1:])
    times = {}
    for bit, name in names.items():
        drive(*(a[:5000] for a in args[:5]), args[5], args[6][:5000], bit)
        times[name] = best_of(repeat, lambda bit=bit: drive(*args, bit))
    return times


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=10_000_000)
    parser.add_argument("--loop-samples", type=int, default=100_000)
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--stages", action="store_true", help="also time the kernel's stages")
    parser.add_argument("--engines", action="store_true", help="also time the other engines")
    args = parser.parse_args()
    n, m = args.samples, min(args.loop_samples, args.samples)
    steps, poses = synthesise(n)
    cov0 = np.zeros((3, 3))
    out = np.zeros((n + 1, 3, 3))  # touched once, so its pages are mapped

    def consume(**options: object) -> np.ndarray:
        last = cov0
        for _, chunk in iter_track_covariance(steps, poses, NOISE, cov0, **options):
            last = chunk[-1]
        return last

    small = BodySteps(steps.dd[:3000], steps.dtheta[:3000], steps.dt[:3000],
                      {k: v[:3000] for k, v in steps.inputs.items()}, steps.robot)
    track_covariance(small, poses[:3001], NOISE, cov0)  # compile (or load numba's cache)
    t_out = best_of(args.repeat, lambda: track_covariance(steps, poses, NOISE, cov0, out=out))
    t_fresh = best_of(args.repeat, lambda: track_covariance(steps, poses, NOISE, cov0))
    t_iter = best_of(args.repeat, consume)
    inputs = (poses[:-1, 2], steps.dd, steps.dtheta, steps.inputs["d_left"], steps.inputs["d_right"])
    floor = best_of(args.repeat, lambda: copy_floor(inputs, out, n))
    lists = [a[:m].tolist() for a in inputs]
    t_loop = best_of(max(2, args.repeat // 2),
                     lambda: plain_loop(*lists, WHEEL_BASE, NOISE.k_left, NOISE.k_right)) * n / m

    got = track_covariance(steps, poses, NOISE, cov0, out=out)[1:m + 1]
    ref = np.array(plain_loop(*lists, WHEEL_BASE, NOISE.k_left, NOISE.k_right))
    upper = got[:, [0, 0, 0, 1, 1, 2], [0, 1, 2, 1, 2, 2]]
    rel = float(np.max(np.abs(upper - ref).max(axis=1) / np.abs(ref).max(axis=1)))

    print(f"{n:,} steps at {RATE_HZ:.0f} Hz ({np.abs(steps.dd).sum() / 1000:.1f} km), per-wheel "
          f"noise; best of {args.repeat}")
    print(f"track_covariance, out=:               {t_out * 1e3:7.1f} ms = {t_out / n * 1e9:5.2f} ns/step")
    print(f"track_covariance, fresh (N, 3, 3):    {t_fresh * 1e3:7.1f} ms")
    print(f"iter_track_covariance (chunks only):  {t_iter * 1e3:7.1f} ms")
    print(f"copy floor (read 5 inputs, write 6 columns): {floor * 1e3:.1f} ms")
    print(f"plain Python loop (on {m:,} steps):  {t_loop * 1e3:7.0f} ms = {t_loop / n * 1e9:5.0f} "
          f"ns/step; max rel. difference {rel:.1e}")
    print(f"ratio vs plain loop:  {t_loop / t_out:.0f}x (out=), {t_loop / t_fresh:.0f}x (fresh), "
          f"{t_loop / t_iter:.0f}x (chunks)   [goal >= 100x]")
    print(f"ratio to copy floor:  {t_out / floor:.2f}x (out=), {t_iter / floor:.2f}x (chunks)"
          f"   [goal <= 3x]")
    if args.stages:
        for name, seconds in stage_times(steps, poses, out, args.repeat).items():
            print(f"  stage {name:<38} {seconds * 1e3:6.1f} ms")
    if args.engines:
        jittered = poses.copy()
        jittered[:, 2] += np.random.default_rng(1).normal(0.0, 1e-9, n + 1)
        for name, run in (("recursion, parallel", lambda: consume(parallel=True)),
                          ("transition", lambda: consume(engine="transition")),
                          ("recursion-fallback", lambda: track_covariance(
                              steps, jittered, NOISE, cov0, out=out))):
            run()
            print(f"  {name:<22} {best_of(max(1, args.repeat // 2), run) * 1e3:7.1f} ms")


if __name__ == "__main__":
    main()
