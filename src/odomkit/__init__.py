"""odomkit: wheeled-robot odometry with honest uncertainty.

The public API is the ``__all__`` of each public module (the documentation's "Python API"
pages, docs/reference/api/, list them all, and ``tests/test_architecture.py`` keeps them true); a name
that is not listed there, and every underscored module or name, may change without notice.

- the core, pure functions on numpy arrays, SI units inside (metres, radians, seconds):
  :mod:`odomkit.robot` and :mod:`odomkit.noise` (parameter sets), :mod:`odomkit.angles`,
  :mod:`odomkit.path`, :mod:`odomkit.log`, :mod:`odomkit.kinematics`,
  :mod:`odomkit.integrate`, :mod:`odomkit.track`, :mod:`odomkit.propagate`,
  :mod:`odomkit.simulate`, :mod:`odomkit.calibrate`, :mod:`odomkit.evaluate`;
- the edges: :mod:`odomkit.io` (every reader and writer), :mod:`odomkit.workflows` (file in,
  core, file out: one function per command), :mod:`odomkit.plot`;
- the command line, :mod:`odomkit.cli` (its interface is the ``odomkit`` commands).

Only the error classes and the version are imported here: ``import odomkit`` loads no
numpy or scipy, so the command line starts fast. Import the modules you use, e.g.
``from odomkit.integrate import dead_reckon``.
"""

from odomkit.errors import InputError, ModelError, OdomkitError

__version__ = "0.1.0"
__all__ = ["OdomkitError", "InputError", "ModelError", "__version__"]
