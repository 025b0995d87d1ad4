"""Monte Carlo validation of the covariance models (Chong–Kleeman section 6.1).

- :func:`simulate_runs`: N noisy runs of a segment path -> final poses (N, 3);
- :func:`monte_carlo`: the same plus the prediction, standard errors, z-scores and a
  consistency verdict; :func:`simulate_sweep` over a grid of settings;
- :class:`SystematicErrors`: Borenstein–Feng E_d, E_b, E_s for calibration experiments
  (:mod:`odomkit.simulate.plan` turns path and noise into kernel coefficients).

Dask (``scheduler=...``) is imported only when asked for.
"""

from odomkit.simulate.engine import MonteCarloRuns, simulate_runs
from odomkit.simulate.experiment import monte_carlo, simulate_sweep, theory_summary
from odomkit.simulate.plan import SystematicErrors
from odomkit.simulate.stats import compare

__all__ = ["MonteCarloRuns", "SystematicErrors", "compare", "monte_carlo", "simulate_runs",
           "simulate_sweep", "theory_summary"]
