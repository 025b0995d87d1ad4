"""One declaration of a group of flags that several commands share, given to each command by
a decorator instead of being written out in every signature.

typer builds a command's options from its signature. :func:`with_flags` gives the typer
app a signature that holds the command's own parameters plus the group's flags (declared
once, as ``(name, Annotated option, default)``), and calls the command with the group
parsed into one value (``log_opts: LogOptions``, ``truth_base: TruthOptions``) in place
of the flags. ``odomkit.cli.log_options.with_log_options`` and
``odomkit.cli.truth_options.with_truth_options`` are the two groups.
"""

from __future__ import annotations

import functools
import inspect
from collections.abc import Callable, Mapping, Sequence
from typing import Any

__all__ = ["Flag", "with_flags"]

Flag = tuple[str, Any, Any]
"""One shared flag: its parameter name, its ``Annotated[type, typer.Option(...)]`` and its
default."""

#: The shared flags go before these parameters, so that ``--force`` and ``--json`` stay last
#: in a command's help.
_LAST = ("force", "json_out")


def _evaluated(command: Callable[..., Any], param: inspect.Parameter) -> inspect.Parameter:
    """``param`` with its annotation evaluated in the command's module (the cli modules use
    ``from __future__ import annotations``; typer needs the objects). A name the module
    imports only for type checking (another group's parsed value, which that group's
    decorator removes) stays a string."""
    annotation = param.annotation
    if isinstance(annotation, str):
        try:
            annotation = eval(annotation, inspect.unwrap(command).__globals__)  # noqa: S307 - own source
        except NameError:
            pass
    return param.replace(annotation=annotation)


Command = Callable[..., Any]


def with_flags(flags: Sequence[Flag], into: str,
               parse: Callable[[Mapping[str, Any]], Any]) -> Callable[[Command], Command]:
    """A decorator giving a command the flags ``flags``, parsed by ``parse`` (from a mapping
    of parameter name to value) into the command's keyword parameter ``into``.

    Examples
    --------
    >>> from typing import Annotated
    >>> import typer
    >>> flag = ("level", Annotated[int, typer.Option("--level")], 1)
    >>> @with_flags([flag], "doubled", lambda v: 2 * v["level"])
    ... def command(name: str, doubled: int = 0) -> str:
    ...     return f"{name} {doubled}"
    >>> list(inspect.signature(command).parameters)
    ['name', 'level']
    >>> command(name="x", level=4)
    'x 8'
    """
    defaults = {name: default for name, _, default in flags}

    def decorate(command: Callable[..., Any]) -> Callable[..., Any]:
        own = inspect.signature(command)
        if into not in own.parameters:
            raise TypeError(f"{command.__name__} must take a parameter {into!r}")
        clash = sorted(set(defaults) & set(own.parameters))
        if clash:
            raise TypeError(f"{command.__name__} declares shared flags itself: {clash}")
        kept = [_evaluated(command, p) for p in own.parameters.values() if p.name != into]
        shared = [inspect.Parameter(name, inspect.Parameter.KEYWORD_ONLY, default=default,
                                    annotation=annotation) for name, annotation, default in flags]
        cut = next((i for i, p in enumerate(kept) if p.name in _LAST), len(kept))
        params = [p.replace(kind=inspect.Parameter.KEYWORD_ONLY) for p in kept]
        params = params[:cut] + shared + params[cut:]

        @functools.wraps(command)
        def wrapper(**kwargs: Any) -> Any:
            values = {name: kwargs.pop(name, default) for name, default in defaults.items()}
            return command(**kwargs, **{into: parse(values)})

        wrapper.__signature__ = inspect.Signature(params)  # type: ignore[attr-defined]
        wrapper.__annotations__ = {p.name: p.annotation for p in params}
        return wrapper

    return decorate
