"""Strategies by name, found through the entry-point group `softevo.strategies`.

The built-ins are registered there by softevo's own `pyproject.toml`, exactly as a user's
package registers its own:

    [project.entry-points."softevo.strategies"]
    my-search = "my_package.search:MySearch"

so `softevo run --algorithm my-search`, `POST /runs`, the library and a takeover all find it
once the package is installed. A name that two packages claim is refused, not shadowed.
"""

from __future__ import annotations

from functools import cache
from importlib.metadata import entry_points
from typing import TypeGuard

from softevo.core.search.strategy import Strategy

GROUP = "softevo.strategies"


class StrategyError(ValueError):
    """A strategy that cannot be found or loaded; the message says which and why."""


@cache
def strategies() -> dict[str, type[Strategy]]:
    """Every installed strategy by name, sorted (loaded once per process)."""
    found: dict[str, type[Strategy]] = {}
    for point in entry_points(group=GROUP):
        if point.name in found:
            raise StrategyError(f"algorithm {point.name!r}: registered twice in {GROUP}")
        try:
            loaded = point.load()
        except Exception as error:
            raise StrategyError(
                f"algorithm {point.name!r}: cannot load {point.value} ({error}; an install "
                "older than its code? pip install --no-deps --no-build-isolation -e .)"
            ) from None
        if not _is_strategy(loaded):
            raise StrategyError(f"algorithm {point.name!r}: {point.value} is not a Strategy")
        missing = sorted(getattr(loaded, "__abstractmethods__", ()))
        if missing:
            raise StrategyError(
                f"algorithm {point.name!r}: {point.value} does not implement "
                f"{', '.join(missing)} (one that breeds whole generations subclasses Generational)"
            )
        if loaded.name != point.name:
            raise StrategyError(
                f"algorithm {point.name!r}: {point.value} calls itself {loaded.name!r}"
            )
        found[point.name] = loaded
    if not found:
        raise StrategyError(f"no strategies installed in {GROUP}: is softevo installed?")
    return dict(sorted(found.items()))


def strategy_class(name: str) -> type[Strategy]:
    """The strategy called `name`; StrategyError lists the installed ones otherwise."""
    installed = strategies()
    if name not in installed:
        raise StrategyError(f"algorithm: unknown {name!r} (installed: {', '.join(installed)})")
    return installed[name]


def _is_strategy(loaded: object) -> TypeGuard[type[Strategy]]:
    return isinstance(loaded, type) and issubclass(loaded, Strategy)
