"""`softevo reproduce --steady`: asynchronous steady-state evolution against the paper's GA
(issue 37), at paper-voxel settings (25 robots a generation), on 4x4x3, 4x4x4 and 3x3x6 x seeds
1-3, through the API.

* **The same simulations.** A paper-voxel GA generation breeds 25 robots but simulates about 5
  (survivors and repeated genomes take their fitness from the cache), and steady-state's births
  repeat genomes at a rate of their own, so equal births are not equal simulations. Round 1
  runs the GA (50 generations, half the paper's) and steady-state for as many births (`long`);
  S, the GA's simulations on that box and seed, is the budget. Round 2 runs steady-state again
  for G rows (`matched`): G is the most rows of the long run that stay within S simulations. A
  shorter steady-state run is the longer one's first rows (births are numbered and bred from
  the seed alone), which is checked, so the matched run is steady-state on the GA's
  simulations, with a wall time of its own.
* **Alone, and beside a GA run.** The private service drives one run at a time (`RUNNING`) on
  a pool of every core, so a run's wall time is its own: the GA waits at every generation's
  barrier, steady-state keeps up to W = P births in flight. Every steady-state run is submitted
  right after a GA run of its box and seed (round 2 runs the GA again, which must give its
  first curve), so that a machine shared with others loads both alike: the wall times are
  compared in those pairs.
* **No evaluation-time bias.** One matched run again in this process (`Evolution` on the local
  pool, the library's code path: the one generation step, the run held in memory), twice: as
  it is, and through `SizeTimed`, which holds each batch k s per voxel of its robots before it
  returns the real fitness, so small robots land first and batches overtake each other. Both
  curves and final states are compared, and the curve with the service's.

The tables and the figure are `steady_report`'s.
"""

from __future__ import annotations

import math
import re
import threading
import time
from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from typing import Any

from softevo.client import Client
from softevo.core.config import resolve
from softevo.core.evaluator import BatchResult, Evaluator
from softevo.core.search.evolution import Evolution

#: Runs the private service drives at once: one, so that wall times are each run's own.
RUNNING = 1
POLL = 0.25  # s between two questions about a run
FULL: dict[str, Any] = {
    "shapes": [[4, 4, 3], [4, 4, 4], [3, 3, 6]],
    "seeds": [1, 2, 3],
    # paper-voxel with half its 100 generations, for both methods: the suite's 27 runs then fit
    # in about 50 minutes on two shared cores
    "settings": {"generations": 50},
    "timed": ([4, 4, 4], 1),
    "per_voxel": 0.004,
}
QUICK: dict[str, Any] = {
    "shapes": [[2, 2, 2]],
    "seeds": [1],
    "settings": {"population": 6, "generations": 4, "sim": {"duration": 1.0, "settle_time": 0.3}},
    "timed": ([2, 2, 2], 1),
    "per_voxel": 0.004,
}
GA, STEADY, LONG = "GA", "steady-state", "steady-state, the GA's births"
METHODS = (GA, STEADY, LONG)
GA_AGAIN = "GA, again"  # round 2's GA, run beside the matched steady-state run
#: The GA run timed beside each method's (the same box and seed, the run before it; for the GA,
#: its second run, whose difference says how much the machine's load moves a wall time).
BESIDE = {GA: GA_AGAIN, STEADY: GA_AGAIN, LONG: GA}
#: A batch's key names the birth it starts with (`core.search.stream.Flights.send`).
_FIRST_BIRTH = re.compile(r"-b(\d+)-")


@dataclass
class Results:
    """What the experiment measured: finished runs and their curves by (box, method, seed), the
    budget (the GA's simulations) and matched rows by (box, seed), and the timing check."""

    plan: dict[str, Any]
    runs: dict[tuple[str, str, int], dict[str, Any]] = field(default_factory=dict)
    curves: dict[tuple[str, str, int], list[dict[str, Any]]] = field(default_factory=dict)
    budgets: dict[tuple[str, int], int] = field(default_factory=dict)
    matched: dict[tuple[str, int], int] = field(default_factory=dict)
    timing: dict[str, Any] = field(default_factory=dict)


def box(shape: Sequence[int]) -> str:
    return "x".join(map(str, shape))


def request(plan: dict[str, Any], shape: list[int], seed: int, method: str) -> dict[str, Any]:
    """The run request of `method` on a box and seed (the matched run's generations apart)."""
    config = {"preset": "paper-voxel", **plan["settings"], "shape": shape, "seed": seed}
    return config if method == GA else {**config, "algorithm": "steady-state"}


def run_steady(client: Client, quick: bool, workers: int | None) -> Results:
    """Both rounds through the API, then the timing check in this process."""
    plan = QUICK if quick else FULL
    results = Results(plan)
    first: dict[tuple[str, str, int], int] = {}
    for shape in plan["shapes"]:
        for seed in plan["seeds"]:  # interleaved, so both methods meet the same machine
            for method in (GA, LONG):
                first[(box(shape), method, seed)] = client.run(
                    **request(plan, shape, seed, method)
                ).id
    _wait(client, results, first)
    second: dict[tuple[str, str, int], int] = {}
    for shape in plan["shapes"]:
        for seed in plan["seeds"]:  # the GA again, so the matched run has one timed beside it
            rows = _match(results, box(shape), seed)
            second[(box(shape), GA_AGAIN, seed)] = client.run(**request(plan, shape, seed, GA)).id
            config = {**request(plan, shape, seed, STEADY), "generations": rows}
            second[(box(shape), STEADY, seed)] = client.run(**config).id
    _wait(client, results, second)
    results.timing = timing_check(results, workers)
    return results


def _wait(client: Client, results: Results, submitted: dict[tuple[str, str, int], int]) -> None:
    """Each run to its end, in the order the service runs them (one request per POLL s, so the
    waiting costs the timed runs next to nothing and loses under POLL s per run)."""
    for done, (key, run_id) in enumerate(submitted.items(), start=1):
        run = client.get_run(run_id).wait(progress=False, poll=POLL)
        print(f"  steady: {done}/{len(submitted)} runs done", flush=True)
        if run["status"] != "completed":
            raise SystemExit(f"softevo reproduce: run {run['id']} ({key}) ended {run['status']}")
        results.runs[key] = run
        results.curves[key] = client.get_run(run["id"]).curve()


def _match(results: Results, name: str, seed: int) -> int:
    """The budget S (the GA's simulations) and the most rows of the long steady-state run whose
    simulations stay within it (at least one)."""
    budget = simulations(results.curves[(name, GA, seed)])
    results.budgets[(name, seed)] = budget
    total, rows = 0, 0
    for row in results.curves[(name, LONG, seed)]:
        total += row["evaluations"]
        if total > budget:
            break
        rows += 1
    results.matched[(name, seed)] = max(1, rows)
    return max(1, rows)


def simulations(curve: list[dict[str, Any]], rows: int | None = None) -> int:
    """Simulations of a curve's first `rows` rows (all by default)."""
    return sum(row["evaluations"] for row in curve[:rows])


def repeated(results: Results, name: str, seed: int) -> bool:
    """Whether the GA run again in round 2 has its first curve, to the last digit."""
    return results.curves[(name, GA, seed)] == results.curves[(name, GA_AGAIN, seed)]


def prefix_holds(results: Results, name: str, seed: int) -> bool:
    """Whether the matched run's curve is the long run's first rows, to the last digit."""
    matched = results.curves[(name, STEADY, seed)]
    return matched == results.curves[(name, LONG, seed)][: len(matched)]


class SizeTimed(Evaluator):
    """A stand-in for workers whose robots take time in proportion to their size: `inner`
    evaluates a batch, which is then held `per_voxel` s per filled voxel of its robots before
    the real fitness returns. Up to `slots` batches at once (holding costs no CPU), so a batch of
    small robots overtakes a batch of large ones sent before it. `landed`: the first birth of
    each batch, in landing order."""

    def __init__(self, inner: Evaluator, per_voxel: float, slots: int) -> None:
        self.inner, self.per_voxel, self.slots = inner, per_voxel, slots
        self.landed: list[int] = []
        self.held = 0.0
        self.lock = threading.Lock()

    def evaluate_batch(
        self, robot_files: Sequence[dict[str, Any]], key: str | None = None
    ) -> BatchResult:
        result = self.inner.evaluate_batch(robot_files, key)
        hold = self.per_voxel * sum(v != "empty" for f in robot_files for v in f["voxels"])
        time.sleep(hold)
        found = _FIRST_BIRTH.search(key or "")
        with self.lock:
            self.held += hold
            if found:
                self.landed.append(int(found.group(1)))
        return result

    def capacity(self) -> int:
        return self.slots

    def close(self) -> None:
        pass  # `inner` is its owner's


def overtaken(landed: list[int]) -> int:
    """Batches that landed after a batch of later births."""
    latest, count = -1, 0
    for first in landed:
        if first < latest:
            count += 1
        latest = max(latest, first)
    return count


def timing_check(results: Results, workers: int | None) -> dict[str, Any]:
    """The matched run of `plan["timed"]` in this process, as it is and size-timed."""
    from softevo.core.physics.evaluation import make_evaluator  # loads the physics: not for --help

    plan = results.plan
    shape, seed = plan["timed"]
    name = box(shape)
    config = resolve(
        {**request(plan, shape, seed, STEADY), "generations": results.matched[(name, seed)]}
    )
    evolutions, walls = [], []
    with make_evaluator(workers) as inner:
        _warm(inner)
        timed = SizeTimed(inner, plan["per_voxel"], 2 * inner.capacity())
        for evaluator in (inner, timed):
            evolution = Evolution.start(config)
            started = time.monotonic()
            evolution.run(evaluator)
            walls.append(time.monotonic() - started)
            evolutions.append(evolution)
    instant, sized = evolutions
    service = results.curves[(name, STEADY, seed)]
    return {
        "box": name,
        "seed": seed,
        "rows": len(instant.curve()),
        "per_voxel": plan["per_voxel"],
        "slots": timed.slots,
        "workers": inner.capacity(),
        "curve_equal": instant.curve() == sized.curve(),
        "state_equal": instant.state.to_json() == sized.state.to_json(),
        "service_equal": same_rows(instant.curve(), service),
        "batches": len(timed.landed),
        "overtaken": overtaken(timed.landed),
        "held_seconds": timed.held,
        "wall_instant": walls[0],
        "wall_timed": walls[1],
        "best": instant.curve()[-1]["best_so_far"],
    }


def _warm(evaluator: Evaluator) -> None:
    """Start every pool process (each loads the kernels) before anything is timed."""
    from softevo.core.robots.robot import VoxelRobot
    from softevo.core.robots.robot_file import robot_to_json
    from softevo.core.robots.settings import sim_settings

    sim = sim_settings({"duration": 0.01, "settle_time": 0})
    file = robot_to_json(VoxelRobot((1, 1, 1), ("hard",), sim=sim))
    slots = evaluator.capacity()
    with ThreadPoolExecutor(slots) as threads:
        list(threads.map(lambda _: evaluator.evaluate_batch([file]), range(slots)))


def same_rows(ours: list[dict[str, Any]], theirs: list[dict[str, Any]]) -> bool:
    """Whether two curves agree in every column both have (NaN and None alike)."""

    def value(v: Any) -> Any:
        return None if isinstance(v, float) and math.isnan(v) else v

    if len(ours) != len(theirs):
        return False
    return all(
        value(a[k]) == value(b[k]) for a, b in zip(ours, theirs, strict=True) for k in a.keys() & b
    )
