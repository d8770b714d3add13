"""The engine in your own process (a notebook, a script): evolve a run whole or generation by
generation, simulate a robot file. It keeps nothing, so it holds the run in memory; `softevo run`
drives the same generation step through the service's store (`softevo.run_store`) and prints this
module's `Result`, and `softevo simulate` is this module plus printing (docs/python.md).

Bad input raises a `ValueError` whose one-line message names the field: `ConfigError` for a run
config, `RobotFileError` for a robot file or the simulation settings given with it, a plain
`ValueError` for `workers` or `trajectory_fps`. Importing this module loads no numba: the physics
is imported by the first call that simulates.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from types import TracebackType
from typing import Any

from softevo.core.config import ConfigError, RunConfig, resolve
from softevo.core.evaluator import Evaluator
from softevo.core.evolution import Evolution, Progress
from softevo.core.nulls import to_null, to_null_record
from softevo.core.robots.robot import Robot, build_mechanics, dropped_voxels
from softevo.core.robots.robot_file import (
    RobotFileError,
    load_robot,
    parse_robot,
    robot_to_json,
    with_sim,
)
from softevo.core.search.front import front_rows

__all__ = [
    "ConfigError",
    "Progress",
    "Result",
    "RobotFileError",
    "Run",
    "configure",
    "evolve",
    "simulate",
    "start",
]


@dataclass(frozen=True)
class Result:
    """A run's outcome as plain JSON values, the files `softevo run` writes: `config`
    (config.json), `curve` (curve.json's rows, also the API's `GET /runs/{id}/curve`), `best`
    (best_robot.json, a softevo.robot/1 file), `state` (state.json), `archive` (archive.json,
    None for a run without descriptors), `measures` (cache.json's: every simulated genome's
    record of measures by genome hash, name -> value or None; docs/physics.md) and
    `best_measures` (the best robot's record)."""

    config: dict[str, Any]
    curve: list[dict[str, Any]]
    best: dict[str, Any] | None
    best_fitness: float | None
    best_generation: int | None
    state: dict[str, Any]
    archive: dict[str, Any] | None
    evaluations: int  # simulations run
    saved: int  # fitness values taken from the run's cache instead
    wall_seconds: float  # simulating and breeding (not writing files), to the ms
    measures: dict[str, dict[str, float | None]] = field(default_factory=dict)
    best_measures: dict[str, float | None] | None = None
    #: a run with objectives: its front, each genome on it once (genome_hash, fitness, measures),
    #: by genome hash; empty for a run without
    front: list[dict[str, Any]] = field(default_factory=list)

    @classmethod
    def of(cls, evolution: Evolution) -> Result:
        """The result of `evolution` so far (finished or not)."""
        best = evolution.best_robot()
        archive = evolution.state.archive
        measures = {key: to_null_record(record) for key, record in evolution.measures.items()}
        best_hash = None if evolution.state.best is None else evolution.state.best[0].hash
        return cls(
            config=evolution.config.to_json(),
            curve=evolution.curve(),
            best=None if best is None else robot_to_json(best[0]),
            best_fitness=None if best is None else best[1],
            best_generation=None if best is None else best[2],
            state=evolution.state.to_json(),
            archive=None if archive is None else archive.to_json(),
            evaluations=evolution.evaluations,
            saved=evolution.saved,
            wall_seconds=round(evolution.elapsed, 3),
            measures=measures,
            best_measures=None if best_hash is None else measures.get(best_hash, {}),
            front=_front(evolution, measures),
        )

    def to_json(self) -> dict[str, Any]:
        """What `softevo run --json` prints (but its `out`)."""
        best: dict[str, Any] | None = None
        if self.best is not None:
            best = {
                "speed": self.best_fitness,
                "generation": self.best_generation,
                "measures": self.best_measures,
                "robot": self.best,
            }
        return {
            "run": self.config,
            "generations": self.curve,
            "best": best,
            "evaluations": self.evaluations,
            "saved": self.saved,
            "wall_seconds": self.wall_seconds,
        }


def _front(
    evolution: Evolution, measures: dict[str, dict[str, float | None]]
) -> list[dict[str, Any]]:
    """The non-dominated set of every genome the run simulated, under its objectives."""
    specs = evolution.config.objectives
    if not specs:
        return []
    rows = [
        {"genome_hash": key, "fitness": to_null(evolution.cache.get(key)), "measures": record}
        for key, record in sorted(measures.items())
    ]
    return front_rows(specs, rows)


class Run:
    """A run in this process, one generation per `step()` (or `for row in run:`). It holds its
    evaluator (`workers` processes, default one per core; 1 = serial, in this process) from the
    first step until `close()` or the end of `finish()`, so stepping pays a pool's start once.
    Pool processes are forked from a fork server that has loaded the physics (spawned where
    there is none, on Windows) and import the main module: a script guards its calls with
    `if __name__ == "__main__":`."""

    def __init__(self, evolution: Evolution, workers: int | None = None) -> None:
        if workers is not None and (isinstance(workers, bool) or workers < 1):
            raise ValueError(f"workers: must be >= 1, got {workers!r}")
        self.evolution = evolution
        self.workers = workers
        self._evaluator: Evaluator | None = None

    @property
    def config(self) -> RunConfig:
        return self.evolution.config

    @property
    def done(self) -> bool:
        """Every generation of the config has run, or its `max_simulations` are reached."""
        return self.evolution.done

    def _evaluate_with(self) -> Evaluator:
        if self._evaluator is None:
            from softevo.core.physics.evaluation import (
                make_evaluator,  # the physics: loaded only to run
            )

            self._evaluator = make_evaluator(self.workers)
        return self._evaluator

    def step(self) -> dict[str, Any]:
        """Evaluate the next generation; its curve row. RuntimeError once the run is done."""
        if self.done:
            if self.evolution.state.generation >= self.config.generations:
                raise RuntimeError(
                    f"the run is done: all {self.config.generations} generations ran"
                )
            raise RuntimeError(
                f"the run is done: its max_simulations ({self.config.max_simulations}) ran"
            )
        self.evolution.step(self._evaluate_with())
        return self.evolution.curve()[-1]

    def __iter__(self) -> Iterator[dict[str, Any]]:
        """The curve rows of the generations still to run, each after it ran."""
        while not self.done:
            yield self.step()

    def finish(self, on_generation: Callable[[Progress], None] | None = None) -> Result:
        """Run the remaining generations, calling `on_generation` after each (what `softevo
        run`'s progress bar shows), then close the evaluator; the result."""
        try:
            if not self.done:
                self.evolution.run(self._evaluate_with(), on_generation)
        finally:
            self.close()
        return self.result()

    def result(self) -> Result:
        """The result so far."""
        return Result.of(self.evolution)

    def close(self) -> None:
        """Stop the evaluator's processes (a later step starts new ones)."""
        if self._evaluator is not None:
            self._evaluator.close()
            self._evaluator = None

    def __enter__(self) -> Run:
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        error: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        self.close()


def configure(config: dict[str, Any] | RunConfig | None = None, **settings: Any) -> RunConfig:
    """The run config of a preset plus overrides, as `POST /runs` takes it (`preset` defaults to
    paper-voxel); `settings` override `config`'s, `sim` key by key. ConfigError names the field."""
    if isinstance(config, RunConfig):
        if not settings:
            return config
        request = config.to_json()
    elif config is None:
        request = {}
    elif isinstance(config, dict):
        request = dict(config)
    else:
        raise ConfigError(f"run config: expected an object, got {type(config).__name__}")
    if isinstance(request.get("sim"), dict) and isinstance(settings.get("sim"), dict):
        settings["sim"] = {**request["sim"], **settings["sim"]}
    return resolve({**request, **settings}, new=True)


def start(
    config: dict[str, Any] | RunConfig | None = None,
    *,
    workers: int | None = None,
    **settings: Any,
) -> Run:
    """A new run, not stepped yet (see `configure` for `config` and `settings`)."""
    return Run(Evolution.start(configure(config, **settings)), workers)


def evolve(
    config: dict[str, Any] | RunConfig | None = None,
    *,
    workers: int | None = None,
    on_generation: Callable[[Progress], None] | None = None,
    **settings: Any,
) -> Result:
    """A whole run, e.g. `evolve(preset="quick", seed=1, generations=5)`: the same curve as
    `softevo run` (and the service) for the same config, on any number of workers."""
    return start(config, workers=workers, **settings).finish(on_generation)


def _robot(robot: dict[str, Any] | str | Path, duration: float | None, terrain: Any) -> Robot:
    """The robot of a file (path) or decoded file (dict), with its sim overrides; a path's
    errors start with the path."""
    try:
        parsed = load_robot(robot) if isinstance(robot, str | Path) else parse_robot(robot)
        if duration is not None:
            parsed = with_sim(parsed, duration=duration)
        if terrain is not None:
            parsed = with_sim(parsed, terrain=terrain)
    except ValueError as error:  # RobotFileError, or a robot the lattice refuses
        message = f"{robot}: {error}" if isinstance(robot, str | Path) else str(error)
        raise RobotFileError(message) from None
    return parsed


def simulate(
    robot: dict[str, Any] | str | Path,
    *,
    duration: float | None = None,
    terrain: dict[str, Any] | None = None,
    trajectory_fps: float | None = None,
) -> dict[str, Any]:
    """Simulate one robot file: what `softevo simulate` prints (masses, springs, steps, com_start,
    com_end, distance, speed, forward_speed, climb_rate, energy, cost_of_transport, wall_seconds,
    stable, dropped_voxels), and with `trajectory_fps` a `trajectory` (softevo.trajectory/1, that
    many frames per simulated second). `duration` and `terrain` override the file's sim."""
    from softevo.core.physics import simulate as run_physics
    from softevo.core.physics.evaluation import (
        warm_up,  # the physics (numba): loaded here, not above
    )

    if trajectory_fps is not None and not (math.isfinite(trajectory_fps) and trajectory_fps > 0):
        raise ValueError(f"trajectory_fps: must be a finite number > 0, got {trajectory_fps!r}")
    parsed = _robot(robot, duration, terrain)
    dropped = dropped_voxels(parsed, build_mechanics(parsed))
    record_every = max(1, round(1.0 / (trajectory_fps * parsed.sim.step))) if trajectory_fps else 0
    warm_up()  # load the compiled kernels first, so wall_seconds times the simulation alone
    result, trajectory = run_physics(parsed, record_every=record_every)
    measures = {**result.to_json(), "dropped_voxels": dropped}
    if trajectory is not None:
        from softevo.core.outputs.replay import finite_part

        kept, blew_up_at = finite_part(trajectory)  # frames up to a blow-up: never NaN in JSON
        measures["trajectory"] = kept.to_json()
        if blew_up_at is not None:  # when the frames stop (s); absent for a sound simulation
            measures["trajectory"]["blew_up_at"] = blew_up_at
    return measures
