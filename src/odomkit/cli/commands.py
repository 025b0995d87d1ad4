"""Import every command module so that it registers itself on the app."""

from odomkit.cli import predict  # noqa: F401
from odomkit.cli import track  # noqa: F401
from odomkit.cli import umbmark  # noqa: F401
