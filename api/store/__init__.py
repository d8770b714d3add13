"""The one store: every SQL statement of softevo lives in this package, and callers (routes, the
coordinator, the SSE stream) speak to it in plain values, never sessions or ORM rows.

* `runs`: runs and sweeps (create, read, list, cancel), curves, individuals, progress;
* `leases`: which coordinator drives a run, and the fence around every driver write;
* `driving`: the coordinator's reads and writes of a generation.
"""

from softevo.api.store import births, driving, leases
from softevo.api.store.runs import (
    ConflictError,
    NotFoundError,
    QueueFullError,
    RunRecord,
    archive,
    best_individual,
    cancel_run,
    create_run,
    create_sweep,
    curve,
    curve_after,
    get_individual,
    get_run,
    get_sweep,
    list_individuals,
    list_runs,
    list_sweeps,
    population_points,
    progress_counts,
)

__all__ = [
    "ConflictError",
    "NotFoundError",
    "QueueFullError",
    "RunRecord",
    "archive",
    "best_individual",
    "births",
    "cancel_run",
    "create_run",
    "create_sweep",
    "curve",
    "curve_after",
    "driving",
    "get_individual",
    "get_run",
    "get_sweep",
    "leases",
    "list_individuals",
    "list_runs",
    "list_sweeps",
    "population_points",
    "progress_counts",
]
