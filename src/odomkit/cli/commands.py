"""Import every command module so that it registers itself on the app."""

from odomkit.cli import (
    calibrate,  # noqa: F401
    check,  # noqa: F401
    demo,  # noqa: F401
    evaluate,  # noqa: F401
    fit_amcl,  # noqa: F401
    fit_noise,  # noqa: F401
    predict,  # noqa: F401
    report,  # noqa: F401
    simulate,  # noqa: F401
    track,  # noqa: F401
    umbmark,  # noqa: F401
)

__all__: list[str] = []
