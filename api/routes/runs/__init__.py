"""The `/runs` resource: one router, its routes in modules by what they do: `lifecycle` (create,
list, read, cancel, the curve, individuals and the best), `archive` and `front` (a run's map and
Pareto front), `views` (replays, pictures and moving pictures)."""

from fastapi import APIRouter

router = APIRouter(prefix="/runs", tags=["runs"])

# Each module adds its routes to `router` as it is imported; in this order they are matched.
from softevo.api.routes.runs import lifecycle  # noqa: E402, F401, I001
from softevo.api.routes.runs import archive, front, views  # noqa: E402, F401
