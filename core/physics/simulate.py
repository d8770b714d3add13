"""Public entry points of the physics engine: validate, build arrays, call a kernel, measure.

`simulate` runs one robot (optionally recording a trajectory); `simulate_batch` runs many robots
that share settings together in the SIMD kernel, split over threads, and gives bit-identical
positions to running each alone (tests/core/physics/test_physics.py checks this).
"""

from __future__ import annotations

import math
import time
from collections import defaultdict
from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np

from softevo.core.limits import SMALL_POINTS
from softevo.core.nulls import to_null, to_nulls
from softevo.core.objectives import OBJECTIVE_MEASURES, STANDARD_GRAVITY
from softevo.core.physics import kernels
from softevo.core.physics.damping import ground_damping, spring_dashpots
from softevo.core.robots.robot import Mechanics, Robot, build_mechanics
from softevo.core.robots.settings import SimSettings
from softevo.core.robots.terrain import kernel_params

#: Robots per `simulate_many` call. 8 doubles fill one AVX-512 vector, and a batch of 8 solid
#: 4x4x4 robots keeps its arrays in a 1 MB L2 cache: 4 to 8 measured fastest, 32 about 30 %
#: slower (bench/physics.py, BENCHMARKS.md).
DEFAULT_LANES = 8
#: A chunk of fewer robots than this, each of at most `SMALL_POINTS` lattice points
#: (`softevo.core.limits`), runs robot by robot in `simulate_one` when `simulate_batch` is asked
#: to (`small_alone`): with so few robots the batched kernel's SIMD lanes stay mostly empty, and
#: one robot at a time cost 0.4-0.8 of it per robot (BENCHMARKS.md, "Small robots"). Same bits
#: either way.
SMALL_WIDTH = 4


@dataclass(frozen=True)
class Trajectory:
    """Mass positions over time, for replays: frames [F, M, 3] (m) at `times` [F] (s)."""

    times: np.ndarray
    frames: np.ndarray
    springs: np.ndarray  # [S, 2] mass indices
    stiffness: np.ndarray  # [S] (N/m), to colour passive springs by material
    phase: np.ndarray | None = None  # [S] actuation phase (rad), NaN for a passive spring

    def to_json(self) -> dict:
        phase = (
            None
            if self.phase is None
            else [None if (q := to_null(p)) is None else round(q, 6) for p in self.phase.tolist()]
        )
        return {
            "format": "softevo.trajectory/1",
            "times": [round(t, 9) for t in self.times.tolist()],
            "springs": self.springs.tolist(),
            "stiffness": self.stiffness.tolist(),
            "phase": phase,
            "frames": np.round(self.frames, 6).tolist(),
        }


@dataclass(frozen=True)
class SimResult:
    """Outcome of one simulation. Fitness is `speed`: NaN when the simulation blew up."""

    masses: int
    springs: int
    steps: int
    com_start: tuple[float, float, float]  # centre of mass at settle_time (m)
    com_end: tuple[float, float, float]  # centre of mass at the end (m)
    distance: float  # net horizontal displacement of the centre of mass (m)
    speed: float  # distance / measured time (m/s)
    wall_seconds: float
    stable: bool  # every position finite at the end, no spring blown past MAX_STRETCH
    final_positions: np.ndarray  # [M, 3] (m)
    forward_speed: float = math.nan  # net displacement along +x / measured time (m/s)
    climb_rate: float = math.nan  # rise of the centre of mass / measured time (m/s)
    energy: float = math.nan  # actuators' work over the measured time (J; NaN: not measured)
    total_mass: float = math.nan  # (kg)
    #: direction of the centre of mass's net horizontal displacement, degrees in [-180, 180]
    #: counter-clockwise from +x (90: +y); 0 for no displacement, NaN when not stable
    heading: float = math.nan

    @property
    def cost_of_transport(self) -> float:
        """energy / (total mass x g x distance): dimensionless, lower is cheaper."""
        weight_distance = self.total_mass * STANDARD_GRAVITY * self.distance
        if not self.stable or math.isnan(self.energy) or weight_distance <= 0:
            return math.nan
        return self.energy / weight_distance

    @property
    def efficiency(self) -> float:
        """distance per joule of actuator work (m/J); 0 for a robot that did no work."""
        if not self.stable or math.isnan(self.energy):
            return math.nan
        return self.distance / self.energy if self.energy > 0 else 0.0

    def measure(self, objective: str) -> float:
        """The fitness of this result under `objective` (softevo.core.objectives)."""
        return float(getattr(self, OBJECTIVE_MEASURES[objective]))

    def measures(self) -> dict[str, float]:
        """Every number this simulation measured, by name (NaN: not measured, or not stable):
        the record kept per individual (job results, the run's cache, the store, population.csv,
        the API), which objectives and behavioural descriptors read by name. The one place that
        defines them; a new measure is one line here and one in docs/physics.md ("Measures and
        objectives"). Not measures: `wall_seconds` and `steps` (of the run, not the robot)."""
        return {
            "distance": self.distance,
            "speed": self.speed,
            "forward_speed": self.forward_speed,
            "climb_rate": self.climb_rate,
            "heading": self.heading,
            "energy": self.energy,
            "cost_of_transport": self.cost_of_transport,
            "efficiency": self.efficiency,
            "stable": 1.0 if self.stable else 0.0,
            "total_mass": self.total_mass,
            "masses": float(self.masses),
            "springs": float(self.springs),
        }

    def to_json(self) -> dict:
        """The `softevo simulate` output (no final positions)."""
        return {
            "masses": self.masses,
            "springs": self.springs,
            "steps": self.steps,
            "com_start": to_nulls(self.com_start),  # null where the simulation blew up
            "com_end": to_nulls(self.com_end),
            "distance": _json_float(self.distance),
            "speed": _json_float(self.speed),
            "forward_speed": _json_float(self.forward_speed),
            "climb_rate": _json_float(self.climb_rate),
            "energy": _json_float(self.energy),
            "cost_of_transport": _json_float(self.cost_of_transport),
            "wall_seconds": self.wall_seconds,
            "stable": self.stable,
        }


_json_float = to_null


def _scalars(mech: Mechanics) -> tuple:
    sim = mech.sim
    return (
        mech.omega,
        sim.step,
        sim.n_steps,
        sim.mass * sim.gravity,
        sim.ground_stiffness,
        ground_damping(sim),
        sim.friction,
        sim.velocity_factor,
        *kernel_params(sim.terrain),
        sim.settle_steps,
    )


#: A spring longer than this many times its longest rest length at the end means the integration
#: blew up (a time step past the stability limit), even if every position is still finite.
MAX_STRETCH = 5.0


def _blown_up(mech: Mechanics, end: np.ndarray) -> bool:
    """Finite but absurd: some spring stretched past MAX_STRETCH x its longest rest length. No
    crawling robot comes near it (springs stay within tens of percent); a robot whose explicit
    integration diverged does, and would otherwise report a huge, meaningless speed."""
    a, b = mech.lattice.springs[:, 0], mech.lattice.springs[:, 1]
    length = np.sqrt(((end[a] - end[b]) ** 2).sum(axis=1))
    longest = mech.rest_length + np.hypot(mech.amp_sin, mech.amp_cos)
    return bool((length > MAX_STRETCH * longest).any())


def _result(
    mech: Mechanics, start: np.ndarray, end: np.ndarray, wall: float, work: np.ndarray | None
) -> SimResult:
    """Build a result from positions [M, 3] at settle time and at the end, and the actuator work
    of every spring in spring order (None: not measured).

    Positions are made C-contiguous first: NumPy sums a column in a different order for other
    layouts, and the centre of mass must not depend on whether the robot ran alone or batched;
    the work is summed from one array in spring order for the same reason.
    """
    start, end = np.ascontiguousarray(start), np.ascontiguousarray(end)
    com_start = start.mean(axis=0)
    com_end = end.mean(axis=0)
    stable = bool(np.isfinite(end).all()) and not _blown_up(mech, end)
    distance = float(np.hypot(*(com_end[:2] - com_start[:2]))) if stable else math.nan
    seconds = mech.sim.measured_time
    moved = (com_end - com_start) / seconds if stable else np.full(3, math.nan)
    energy = math.nan if work is None else float(np.sum(np.ascontiguousarray(work)))
    return SimResult(
        masses=mech.n_masses,
        springs=mech.n_springs,
        steps=mech.sim.n_steps,
        com_start=tuple(float(v) for v in com_start),
        com_end=tuple(float(v) for v in com_end),
        distance=distance,
        speed=distance / seconds,
        wall_seconds=wall,
        stable=stable,
        final_positions=end,
        forward_speed=float(moved[0]),
        climb_rate=float(moved[2]),
        energy=energy,
        total_mass=mech.n_masses * mech.sim.mass,
        heading=_heading(com_end[:2] - com_start[:2]) if stable else math.nan,
    )


def _heading(shift: np.ndarray) -> float:
    """The direction (degrees, [-180, 180], counter-clockwise from +x) of a horizontal shift
    (dx, dy): atan2 of the net displacement itself, so it is the same bits whoever computes it
    from the same centres of mass."""
    return math.degrees(math.atan2(float(shift[1]), float(shift[0])))


def simulate(
    robot: Robot | Mechanics, *, record_every: int = 0, energy: bool = True
) -> tuple[SimResult, Trajectory | None]:
    """Simulate one robot; with `record_every` > 0 also return positions every that many steps;
    `energy`: measure the actuators' work (a little slower)."""
    mech = robot if isinstance(robot, Mechanics) else build_mechanics(robot)
    n_steps = mech.sim.n_steps
    pos = np.ascontiguousarray(mech.positions.T)  # [3, M]
    vel = np.zeros_like(pos)
    settle = np.empty_like(pos)
    n_frames = len(range(0, n_steps, record_every)) + 1 if record_every > 0 else 0
    frames = np.empty((n_frames, 3, mech.n_masses))
    step_factor = np.full(mech.n_masses, mech.sim.step / mech.sim.mass)
    *scalars, settle_step = _scalars(mech)
    springs = mech.lattice.springs
    work = np.zeros(mech.n_springs if energy else 0)
    started = time.perf_counter()
    kernels.simulate_one(
        pos[0],
        pos[1],
        pos[2],
        vel[0],
        vel[1],
        vel[2],
        step_factor,
        np.ascontiguousarray(springs[:, 0]),
        np.ascontiguousarray(springs[:, 1]),
        mech.stiffness,
        mech.rest_length,
        mech.amp_sin,
        mech.amp_cos,
        spring_dashpots(mech),
        *scalars,
        settle_step,
        settle[0],
        settle[1],
        settle[2],
        record_every,
        frames,
        work,
    )
    wall = time.perf_counter() - started
    result = _result(mech, settle.T, pos.T.copy(), wall, work if energy else None)
    if not record_every:
        return result, None
    times = np.array([*range(0, n_steps, record_every), n_steps], dtype=np.float64) * mech.sim.step
    trajectory = Trajectory(
        times=times,
        frames=frames.transpose(0, 2, 1).copy(),
        springs=springs,
        stiffness=mech.stiffness,
        phase=np.where(
            np.hypot(mech.amp_sin, mech.amp_cos) > 0,
            np.arctan2(mech.amp_cos, mech.amp_sin),
            np.nan,
        ),
    )
    return result, trajectory


def _box_offsets(box: tuple[int, int, int]) -> np.ndarray:
    """Distinct positive index offsets of a point's 26 neighbours in a box of points, ascending.

    Offsets are lattice index differences: one offset may serve two directions (in a box 2
    points wide, +1 is the +x neighbour of x = 0 and the (-x, +y) neighbour of x = 1).
    """
    bx, by, _ = box
    steps = (-1, 0, 1)
    offsets = {dx + bx * (dy + by * dz) for dz in steps for dy in steps for dx in steps}
    return np.array(sorted(o for o in offsets if o > 0), dtype=np.int64)


def _run_group(group: list[Mechanics], energy: bool) -> list[SimResult]:
    """Run robots that share settings and omega in one `simulate_many` call.

    The kernel works on the bounding box of the robots' lattice points, numbered x fastest like
    the lattice, with each spring in its slot (offset index q, first point); see `kernels`.
    """
    first = group[0]
    nx, ny, nz = first.lattice.shape
    grid = (nz + 1, ny + 1, nx + 1)
    edge = first.sim.edge_length
    # Lattice coordinates (x, y, z) of every robot's points, and their bounding box.
    coords = [np.stack(np.unravel_index(m.lattice.points, grid)[::-1], axis=1) for m in group]
    low = np.min([c.min(axis=0) for c in coords], axis=0)
    box = tuple(int(v) for v in np.max([c.max(axis=0) for c in coords], axis=0) - low + 1)
    bx, by, bz = box
    offsets = _box_offsets(box)
    n_points, n_robots = bx * by * bz, len(group)

    # Points a robot lacks sit at their own lattice point (distinct from its masses), never move.
    box_xyz = np.stack(np.unravel_index(np.arange(n_points), (bz, by, bx))[::-1], axis=1) + low
    pos = np.repeat((box_xyz.T * edge)[:, :, None], n_robots, axis=2)  # [3, P, B]
    step_factor = np.zeros((n_points, n_robots))
    damped = first.sim.material_damping > 0.0
    params = np.zeros((5 if damped else 4, len(offsets), n_points, n_robots))
    box_rows, slots = [], []
    for r, (mech, c) in enumerate(zip(group, coords, strict=True)):
        rel = c - low
        rows = rel[:, 0] + bx * (rel[:, 1] + by * rel[:, 2])  # box index of each mass, ascending
        first_end, second_end = rows[mech.lattice.springs.T]
        slot = np.searchsorted(offsets, second_end - first_end)
        lift = mech.positions[0, 2] - mech.lattice.rest_positions[0, 2] * edge
        pos[2, :, r] += lift
        pos[:, rows, r] = mech.positions.T
        step_factor[rows, r] = mech.sim.step / mech.sim.mass
        columns = (mech.stiffness, mech.rest_length, mech.amp_sin, mech.amp_cos)
        params[:, slot, first_end, r] = (*columns, spring_dashpots(mech))[: len(params)]
        box_rows.append(rows)
        slots.append((slot, first_end))  # each spring's slot, in spring order
    vel = np.zeros_like(pos)
    settle = np.empty_like(pos)
    work = np.zeros(params.shape[1:] if energy else (0, 0, 0))
    started = time.perf_counter()
    kernels.simulate_many(
        pos[0],
        pos[1],
        pos[2],
        vel[0],
        vel[1],
        vel[2],
        step_factor,
        offsets,
        params[0],
        params[1],
        params[2],
        params[3],
        params[4] if damped else np.zeros((0, 0, 0)),
        *_scalars(first),
        settle[0],
        settle[1],
        settle[2],
        work,
    )
    wall = (time.perf_counter() - started) / n_robots
    results = []
    for r, (mech, rows, (slot, first_end)) in enumerate(zip(group, box_rows, slots, strict=True)):
        spring_work = work[slot, first_end, r] if energy else None
        results.append(
            _result(mech, settle[:, rows, r].T, pos[:, rows, r].T.copy(), wall, spring_work)
        )
    return results


def _small(group: list[Mechanics]) -> bool:
    """A chunk that `simulate_one` runs faster robot by robot (`SMALL_WIDTH`, `SMALL_POINTS`)."""
    return len(group) < SMALL_WIDTH and all(
        len(mech.lattice.points) <= SMALL_POINTS for mech in group
    )


def _group_key(mech: Mechanics) -> tuple[tuple[int, int, int], SimSettings, float]:
    return (mech.lattice.shape, mech.sim, mech.omega)


def simulate_batch(
    robots: Sequence[Robot | Mechanics],
    *,
    threads: int = 1,
    lanes: int = DEFAULT_LANES,
    energy: bool = False,
    small_alone: bool = False,
) -> list[SimResult]:
    """Simulate many robots; results in input order.

    Robots with the same grid shape, settings and actuation frequency run together, `lanes` at a
    time in the SIMD kernel; chunks run on `threads` threads (the kernel releases the GIL).
    `wall_seconds` of each result is its share of its chunk's time. `energy`: measure the
    actuators' work too (the kernel's extra loop costs time; fitness by `speed` does not need it).
    `small_alone`: a chunk of fewer than `SMALL_WIDTH` small robots runs one robot at a time
    (`simulate`), which is faster for them and gives the same bits.
    """
    if threads < 1 or lanes < 1:
        raise ValueError(f"threads and lanes must be >= 1, got {threads} and {lanes}")
    mechs = [r if isinstance(r, Mechanics) else build_mechanics(r) for r in robots]
    groups: dict[tuple, list[int]] = defaultdict(list)
    for index, mech in enumerate(mechs):
        groups[_group_key(mech)].append(index)
    chunks = []
    for members in groups.values():
        width = min(lanes, -(-len(members) // threads))
        chunks += [members[start : start + width] for start in range(0, len(members), width)]
    results: list[SimResult | None] = [None] * len(mechs)

    def run(chunk: list[int]) -> None:
        group = [mechs[i] for i in chunk]
        if small_alone and _small(group):
            found = [simulate(mech, energy=energy)[0] for mech in group]
        else:
            found = _run_group(group, energy)
        for index, result in zip(chunk, found, strict=True):
            results[index] = result

    if threads == 1 or len(chunks) == 1:
        for chunk in chunks:
            run(chunk)
    else:
        with ThreadPoolExecutor(max_workers=threads) as pool:
            list(pool.map(run, chunks))
    return results  # type: ignore[return-value]
