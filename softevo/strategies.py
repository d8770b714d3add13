"""What a search strategy of your own package imports: the protocol (`Generational` for one
that breeds whole generations; `Strategy` and a `Cohort` of its own for one told birth by birth),
its state, and the built-in variation it may reuse. Register the class in your `pyproject.toml`:

    [project.entry-points."softevo.strategies"]
    my-search = "my_package.search:MySearch"

and `softevo run --algorithm my-search`, `POST /runs`, `softevo.library.evolve` and the
service's takeover of a run all find it (docs/evolution.md, "A strategy of your own").
"""

from __future__ import annotations

from softevo.core.search import operators
from softevo.core.search.cohort import Birth, Cohort, Told, tell_row
from softevo.core.search.registry import GROUP, StrategyError, strategies, strategy_class
from softevo.core.search.state import Individual, StrategyState
from softevo.core.search.strategy import Generational, NoOptions, Records, Strategy
from softevo.core.search.variation import mate, mutant

__all__ = [
    "GROUP",
    "Birth",
    "Cohort",
    "Generational",
    "Individual",
    "NoOptions",
    "Records",
    "Strategy",
    "StrategyError",
    "StrategyState",
    "Told",
    "mate",
    "mutant",
    "operators",
    "strategies",
    "strategy_class",
    "tell_row",
]
