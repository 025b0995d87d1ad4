"""odomkit: wheeled-robot odometry with honest uncertainty.

Pure maths lives in ``robot``, ``noise``, ``path``, ``kinematics``, ``integrate``,
``propagate``, ``simulate``, ``calibrate`` and ``evaluate``; files in ``io``; the command
line in ``cli``. Everything is SI (metres, radians, seconds) inside.
"""

from odomkit.errors import InputError, ModelError, OdomkitError

__version__ = "0.1.0"
__all__ = ["OdomkitError", "InputError", "ModelError", "__version__"]
