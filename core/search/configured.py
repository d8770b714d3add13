"""The search settings with their strategy checked (`StrategySettings`), and the strategy that
runs them.

`StrategySettings` is `SearchSettings` (`softevo.core.search.settings`: population, generations,
selection, variation rates, descriptors, `algorithm`, the name of a strategy installed in
the entry-point group `softevo.strategies`, and `options`, that strategy's own settings. Each
algorithm is a module of its own (`softevo.core.search.paper_ga`, `random_search`, `hillclimb`,
`map_elites`, or a user's package); `make_strategy` builds the one a config names. With
descriptors, any algorithm keeps an archive beside it, for comparison.
"""

from __future__ import annotations

from typing import Any

from pydantic import ValidationError, model_validator

from softevo.core.limits import MAX_OPTIONS
from softevo.core.robots.encodings import Encoding
from softevo.core.search.registry import StrategyError, strategies, strategy_class
from softevo.core.search.settings import SearchSettings
from softevo.core.search.state import Individual, StrategyState, generation_rng
from softevo.core.search.strategy import Strategy

__all__ = [
    "Individual",
    "SearchSettings",
    "Strategy",
    "StrategySettings",
    "StrategyState",
    "generation_rng",
    "make_strategy",
]


class StrategySettings(SearchSettings):
    """The search settings with the strategy they name checked: it is installed, takes these
    settings and validates its own options (what `POST /runs` and `softevo run` build)."""

    @model_validator(mode="after")
    def _archive(self) -> StrategySettings:
        """The named strategy exists, takes these settings and validates its own options; then
        the archive's settings are checked (this validator replaces `SearchSettings`' one of the
        same name, so a strategy's own message comes first, as it always did)."""
        if len(self.options) > MAX_OPTIONS:
            raise ValueError(f"options: at most {MAX_OPTIONS} settings, got {len(self.options)}")
        try:
            found = strategy_class(self.algorithm)
        except StrategyError as error:
            raise ValueError(str(error)) from None
        found.check(self)
        try:
            found.Options.model_validate(self.options)
        except ValidationError as error:
            problems = "; ".join(
                f"options.{'.'.join(map(str, item['loc']))}: {item['msg']}"
                for item in error.errors()
            )
            raise ValueError(f"{problems} (algorithm {self.algorithm})") from None
        self.check_archive()
        return self


def make_strategy(config: StrategySettings, encoding: Encoding) -> Strategy:
    """The strategy `config.algorithm` names, for `encoding`."""
    return strategy_class(config.algorithm)(config, encoding)


def describe_strategies() -> list[dict[str, Any]]:
    """Every installed strategy as `GET /algorithms` shows it: name, summary, the shared
    settings it reads (with their defaults and descriptions) and its own options' schema."""
    shared = StrategySettings.model_fields
    described = []
    for strategy in strategies().values():
        entry = strategy.describe()
        entry["uses"] = [
            {
                "name": name,
                "default": _plain(shared[name].get_default(call_default_factory=True)),
                "description": shared[name].description or "",
            }
            for name in strategy.uses
        ]
        described.append(entry)
    return described


def _plain(value: Any) -> Any:
    return list(value) if isinstance(value, tuple) else value
