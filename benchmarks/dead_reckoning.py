"""Dead reckoning of 10^7 samples against a plain Python loop and a memory-bandwidth floor.

Prints, each the minimum over ``--repeat`` runs (the least disturbed by other processes
on a shared machine, as timeit does):

* odomkit: wheel travels -> poses by :func:`odomkit.integrate.dead_reckon_wheels`, into a
  preallocated output (``out=``) and into a fresh one (what a plain call gets: the
  operating system must then also map 240 MB of new pages), and the two-step
  ``diff_body_steps`` + ``dead_reckon`` for comparison;
* the fastest plain-Python loop (floats from lists, ``math.sin``/``math.cos``), on a
  prefix of the log (it would take minutes on all of it); ratios are per sample;
* the copy floor: reading the inputs and writing the outputs once, as ``np.copyto`` of
  the very bytes (the two input arrays copied into the output's memory, the rest of the
  output filled), into the same preallocated output and into a fresh one. No dead
  reckoning can beat it: it reads and writes what any must.
* ``--stages``: the kernel's four stages (:mod:`odomkit._integrate_numba`) timed alone.

Goals (issue 10): at least 100x the loop, and within 3x of the floor.

    .venv/bin/python benchmarks/dead_reckoning.py [--samples 10000000] [--repeat 7] [--stages]
"""

from __future__ import annotations

import argparse
import math
import time
from collections.abc import Callable

import numpy as np

from odomkit.integrate import dead_reckon, dead_reckon_wheels
from odomkit.kinematics import diff_body_steps

WHEEL_BASE = 0.3


def plain_loop(d_left: list[float], d_right: list[float], wheel_base: float,
               pose0: tuple[float, float, float]) -> list[tuple[float, float, float]]:
    """The textbook implementation: one exact-arc step per sample, in Python floats."""
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
    return out


def best_of(repeat: int, run: Callable[[], object]) -> float:
    """Minimum wall time of ``repeat`` calls [s]."""
    best = math.inf
    for _ in range(repeat):
        start = time.perf_counter()
        run()
        best = min(best, time.perf_counter() - start)
    return best


def copy_floor(inputs: tuple[np.ndarray, ...], out: np.ndarray) -> None:
    """Read every input byte once and write every output byte once: the inputs are copied
    into the output's memory, the rest of the output is filled."""
    raw = out.reshape(-1).view(np.uint8)
    offset = 0
    for a in inputs:
        np.copyto(raw[offset:offset + a.nbytes], a.view(np.uint8))
        offset += a.nbytes
    raw[offset:].fill(0)


def stage_times(d_left: np.ndarray, d_right: np.ndarray, out: np.ndarray, repeat: int) -> dict:
    """Each stage of the kernel run alone over the whole log [s] (numba driver)."""
    from numba import njit

    from odomkit import _integrate_numba as k

    @njit
    def drive(first, second, out, stages):  # pragma: no cover - benchmark only
        w = np.zeros(k.WORK)
        x = y = theta = 0.0
        for c0 in range(0, first.size, k.CHUNK):
            m = min(k.CHUNK, first.size - c0)
            if stages & 1:
                k._load(first, second, k.WHEELS, 1.0, 1.0, WHEEL_BASE, c0, m, w)
            if stages & 2:
                k._anchors(w, theta)
            if stages & 4:
                k._turn_short(w, k.EXACT)
            if stages & 8:
                x, y, theta = k._emit(w, c0, m, x, y, theta, out, first.size >= k.STREAM_FROM)

    names = {1: "load (read inputs, form dd, dtheta)", 2: "anchors (cos/sin every 128 steps)",
             4: "turn (heading vectors, SIMD lanes)", 8: "emit (sum theta, x, y; write rows)"}
    times = {}
    for bit, name in names.items():
        drive(d_left[:5000], d_right[:5000], out, bit)
        times[name] = best_of(repeat, lambda bit=bit: drive(d_left, d_right, out, bit))
    return times


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=10_000_000)
    parser.add_argument("--loop-samples", type=int, default=200_000)
    parser.add_argument("--repeat", type=int, default=7)
    parser.add_argument("--stages", action="store_true", help="also time the kernel's stages")
    args = parser.parse_args()
    rng = np.random.default_rng(0)
    n, m = args.samples, min(args.loop_samples, args.samples)
    # Smoothly varying wheel speeds at 100 Hz, as from a real robot, with reversals.
    t = np.arange(n) * 0.01
    d_left = 0.004 * np.sin(0.05 * t) + 0.0005 * rng.standard_normal(n)
    d_right = 0.004 * np.sin(0.05 * t + 0.3) + 0.0005 * rng.standard_normal(n)
    out = np.zeros((n + 1, 3))  # touched once, so its pages are mapped

    # Compile (or load from numba's disk cache) outside the timing.
    dead_reckon_wheels(d_left[:30_000], d_right[:30_000], WHEEL_BASE, engine="numba")
    dead_reckon(d_left[:30_000], d_right[:30_000], engine="numba")

    def two_step() -> np.ndarray:
        dd, dtheta = diff_body_steps(d_left, d_right, WHEEL_BASE)
        return dead_reckon(dd, dtheta)

    t_out = best_of(args.repeat, lambda: dead_reckon_wheels(d_left, d_right, WHEEL_BASE, out=out))
    t_fresh = best_of(args.repeat, lambda: dead_reckon_wheels(d_left, d_right, WHEEL_BASE))
    t_two = best_of(args.repeat, two_step)
    f_out = best_of(args.repeat, lambda: copy_floor((d_left, d_right), out))
    f_fresh = best_of(args.repeat, lambda: copy_floor((d_left, d_right), np.empty((n + 1, 3))))
    lists = d_left[:m].tolist(), d_right[:m].tolist()
    t_loop = best_of(max(2, args.repeat // 3),
                     lambda: plain_loop(*lists, WHEEL_BASE, (0.0, 0.0, 0.0))) * n / m

    poses = dead_reckon_wheels(d_left, d_right, WHEEL_BASE)
    ref = np.array(plain_loop(*lists, WHEEL_BASE, (0.0, 0.0, 0.0)))
    agree = float(np.max(np.abs(poses[: m + 1] - ref)))
    mb = (d_left.nbytes + d_right.nbytes) / 1e6, poses.nbytes / 1e6

    print(f"{n:,} samples; inputs {mb[0]:.0f} MB read, poses {mb[1]:.0f} MB written; "
          f"best of {args.repeat}")
    print(f"odomkit dead_reckon_wheels, out=:      {t_out * 1e3:7.1f} ms  "
          f"= {t_out / n * 1e9:5.2f} ns/sample")
    print(f"odomkit dead_reckon_wheels, fresh out: {t_fresh * 1e3:7.1f} ms")
    print(f"diff_body_steps + dead_reckon:         {t_two * 1e3:7.1f} ms")
    print(f"copy floor into out= / fresh memory:   {f_out * 1e3:7.1f} ms / {f_fresh * 1e3:.1f} ms")
    print(f"plain Python loop (on {m:,} samples):  {t_loop * 1e3:7.0f} ms "
          f"= {t_loop / n * 1e9:5.0f} ns/sample; max |difference| {agree:.1e}")
    print(f"ratio vs plain loop:  {t_loop / t_out:.0f}x (out=), {t_loop / t_fresh:.0f}x (fresh), "
          f"{t_loop / t_two:.0f}x (two-step)   [goal >= 100x]")
    print(f"ratio to copy floor:  {t_out / f_out:.2f}x (out=), {t_fresh / f_fresh:.2f}x (fresh)"
          f"   [goal <= 3x]")
    if args.stages:
        for name, seconds in stage_times(d_left, d_right, out, args.repeat).items():
            print(f"  stage {name:<38} {seconds * 1e3:6.1f} ms")


if __name__ == "__main__":
    main()
