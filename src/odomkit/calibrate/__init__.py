"""Calibration of systematic odometry errors.

Modules (import them directly; nothing is imported eagerly here):

- :mod:`odomkit.calibrate.umbmark` — Borenstein–Feng's UMBmark (bidirectional square):
  centres of gravity, E_max,syst, α, β, R, E_d, E_b, c_L, c_R, the corrected wheel base,
  the 3·SEM rule; Chong–Kleeman's variant side by side.
- :mod:`odomkit.calibrate.virtual` — a simulated differential robot that drives the
  UMBmark square by its own odometry, for testing calibrations (virtual UMBmark).
- :mod:`odomkit.calibrate.exact`, :mod:`odomkit.calibrate.noise_fit`,
  :mod:`odomkit.calibrate.export` — exact-model least squares (its residuals and their
  Jacobian in :mod:`odomkit.calibrate.residuals`), (k_L, k_R) fitting and export of
  calibrated robots.
"""

__all__: list[str] = []
