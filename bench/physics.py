"""Physics benchmark: `python bench/physics.py [--quick]`.

Prints spring updates per second (springs x steps x robots / wall seconds, median of a few runs)
for a solid 4x4x4 block of hard voxels (125 masses, 1036 springs), 20,000 steps (10 s at
dt = 0.0005), through:

* `simulate`, one robot (the `simulate_one` kernel);
* `simulate_batch`, 32 such robots, on 1 and on 2 threads (the `simulate_many` kernel), per core
  and in total, and on one thread for several lane counts;
* a plain vectorised NumPy implementation of the same physics, written below (one NumPy pass per
  step over all springs, `np.bincount` to sum forces), for 1 robot and for 32 robots at once;
* `simulate_batch` on each task preset's terrain against flat in the same run (`terrain_rates`),
  for 32 such blocks (the target: every terrain >= 80 % of flat) and for 32 random actuated
  robots of the same springs, whose masses move;

then the speed-ups, and the first-call time (the JIT compile) in a fresh process with an empty
numba cache against a second fresh process that reuses that cache. Timings pass prebuilt
`Mechanics`, so they measure the engine, not building robots. `--quick` runs fewer steps and
repetitions (the figures are noisier). Results on the 2-core machine: BENCHMARKS.md.
"""

from __future__ import annotations

import argparse
import functools
import json
import math
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import textwrap
import time
from pathlib import Path

import numba
import numpy as np

from softevo.core.physics import integrate, kernels, simulate, simulate_batch
from softevo.core.robots.robot import Actuation, Mechanics, VoxelRobot, build_mechanics
from softevo.core.robots.settings import SimSettings
from softevo.core.robots.tasks import TASKS

ROOT = Path(__file__).resolve().parent.parent
TARGETS = {"batch_per_core": 300e6, "single": 150e6}


def cpu_model() -> str:
    try:
        out = subprocess.run(["lscpu"], capture_output=True, text=True, check=True).stdout
    except (OSError, subprocess.CalledProcessError):
        return platform.processor() or platform.machine()
    for line in out.splitlines():
        if line.startswith("Model name:"):
            return line.split(":", 1)[1].strip()
    return platform.machine()


def bench_sim(duration: float, terrain: dict | None = None) -> SimSettings:
    return SimSettings.model_validate(
        {
            "duration": duration,
            "settle_time": min(1.0, duration / 2),
            **({"terrain": terrain} if terrain else {}),
        }
    )


def solid_block(duration: float, terrain: dict | None = None) -> Mechanics:
    return build_mechanics(VoxelRobot((4, 4, 4), ("hard",) * 64, sim=bench_sim(duration, terrain)))


def random_robots(duration: float, terrain: dict | None, count: int) -> list[Mechanics]:
    """`count` random actuated 4x4x4 robots with no empty voxel (the block's 1036 springs each,
    the same robots on every terrain), so contact is also timed on masses that move."""
    rng = np.random.default_rng(5)
    sim = bench_sim(duration, terrain)
    labels = [
        tuple(rng.choice(["hard", "soft", "sine", "neg_sine"], 64).tolist()) for _ in range(count)
    ]
    return [
        build_mechanics(VoxelRobot((4, 4, 4), voxels, Actuation(0.0, 1.0, 0.0), sim))
        for voxels in labels
    ]


def terrain_rates(
    duration: float, repeats: int, n_batch: int, actuated: bool = False
) -> dict[str, float]:
    """Spring updates per second of `n_batch` blocks (or, `actuated`, random actuated robots) on
    each task's terrain, 1 thread, the terrains interleaved round by round so a drifting
    machine hits them alike."""

    def robots(terrain: dict | None) -> list[Mechanics]:
        if actuated:
            return random_robots(duration, terrain, n_batch)
        return [solid_block(duration, terrain)] * n_batch

    batches = {"flat": robots(None)}
    for name, (_, terrain, _) in TASKS.items():
        if terrain["kind"] != "flat":
            batches[name.removeprefix("task-")] = robots(terrain)
    times: dict[str, list[float]] = {name: [] for name in batches}
    for batch in batches.values():
        simulate_batch(batch[:2])  # compiled, and every terrain's path warm
    for _ in range(repeats):
        for name, batch in batches.items():
            started = time.perf_counter()
            simulate_batch(batch)
            times[name].append(time.perf_counter() - started)
    first = batches["flat"][0]
    updates = first.n_springs * first.sim.n_steps * n_batch
    return {name: updates / statistics.median(t) for name, t in times.items()}


LAST: dict = {}  # the last result of each timed run, by label, to check bit-identity


def median_seconds(run, repeats: int, label: str = "") -> float:
    times = []
    for _ in range(repeats):
        started = time.perf_counter()
        LAST[label] = run()
        times.append(time.perf_counter() - started)
    return statistics.median(times)


# --- The same physics in plain vectorised NumPy ---------------------------------------------


def numpy_simulate(mechs: list[Mechanics], n_steps: int) -> np.ndarray:
    """Run robots of one lattice for n_steps, vectorised over springs and robots; [B, M, 3].

    Same equations as the kernels (docs/physics.md, "One step"); forces are summed with
    `np.bincount`, so the order of additions differs and results agree to rounding only.
    """
    first = mechs[0]
    sim, lattice = first.sim, first.lattice
    n_masses, n_robots = lattice.n_masses, len(mechs)
    a, b = lattice.springs[:, 0], lattice.springs[:, 1]
    lanes = np.arange(n_robots)
    at_a = (a[:, None] * n_robots + lanes).ravel()  # flat index of (mass, robot)
    at_b = (b[:, None] * n_robots + lanes).ravel()
    k, rest, amp_s, amp_c = (
        np.stack([getattr(m, name) for m in mechs], axis=1)  # [S, B]
        for name in ("stiffness", "rest_length", "amp_sin", "amp_cos")
    )
    x = np.stack([m.positions for m in mechs], axis=2).transpose(1, 0, 2).copy()  # [3, M, B]
    v = np.zeros_like(x)
    h, dt, omega = sim.step / sim.mass, sim.step, first.omega
    weight, size = sim.mass * sim.gravity, n_masses * n_robots
    for step in range(n_steps):
        t = step * dt
        delta = x[:, b] - x[:, a]  # [3, S, B]
        d = np.sqrt((delta * delta).sum(axis=0))
        length0 = rest + amp_s * math.sin(omega * t) + amp_c * math.cos(omega * t)
        part = (k * (d - length0) / np.maximum(d, kernels.D_MIN)) * delta
        force = np.empty_like(x)
        for c in range(3):
            flat = part[c].ravel()
            force[c] = (np.bincount(at_a, flat, size) - np.bincount(at_b, flat, size)).reshape(
                n_masses, n_robots
            )
        normal = sim.ground_stiffness * np.maximum(-x[2], 0.0)
        u = v + force * h
        u[2] += (weight + normal) * h
        speed = np.sqrt(u[0] ** 2 + u[1] ** 2)
        slip = np.maximum(1.0 - sim.friction * normal * h / np.maximum(speed, integrate.V_MIN), 0.0)
        u[0] *= slip
        u[1] *= slip
        v = u * sim.damping
        x += v * dt
    return x.transpose(2, 1, 0)


# --- Compile time: fresh processes, empty and then warm numba cache --------------------------

FIRST_CALL_SCRIPT = textwrap.dedent(
    """
    import json, time
    started = time.perf_counter()
    from softevo.core.physics import kernels, simulate, simulate_batch
    from softevo.core.robots.robot import VoxelRobot
    from softevo.core.robots.settings import SimSettings
    imported = time.perf_counter() - started
    robot = VoxelRobot((2, 2, 2), ("hard",) * 8, sim=SimSettings(duration=0.01, settle_time=0.0))
    started = time.perf_counter()
    simulate(robot)
    one = time.perf_counter() - started
    started = time.perf_counter()
    simulate_batch([robot, robot])
    many = time.perf_counter() - started
    stats = {name: getattr(kernels, name).stats for name in ("simulate_one", "simulate_many")}
    print(json.dumps({
        "import": imported, "simulate": one, "simulate_batch": many,
        "hits": sum(sum(s.cache_hits.values()) for s in stats.values()),
        "misses": sum(sum(s.cache_misses.values()) for s in stats.values()),
    }))
    """
)


def first_call(cache_dir: str) -> dict:
    env = {**os.environ, "NUMBA_CACHE_DIR": cache_dir}
    out = subprocess.run(
        [sys.executable, "-c", FIRST_CALL_SCRIPT],
        capture_output=True,
        text=True,
        check=True,
        env=env,
        cwd=ROOT,
    ).stdout
    return json.loads(out.strip().splitlines()[-1])


# --- Report ----------------------------------------------------------------------------------


def rate_row(label: str, updates: float, seconds: float, cores: int) -> float:
    rate = updates / seconds
    print(f"  {label:<44}{rate / cores / 1e6:>12.0f}{rate / 1e6:>12.0f}{seconds:>10.3f}")
    return rate / cores


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer steps and repetitions")
    args = parser.parse_args()
    duration = 2.0 if args.quick else 10.0
    repeats = 3 if args.quick else 5
    numpy_steps = (200, 50) if args.quick else (1000, 200)  # one robot, 32 robots
    n_batch = 32

    mech = solid_block(duration)
    n_springs, n_steps = mech.n_springs, mech.sim.n_steps
    batch = [mech] * n_batch
    print(
        f"machine: {os.cpu_count()} cores, {cpu_model()}; Python {platform.python_version()}, "
        f"numba {numba.__version__}, NumPy {np.__version__}"
    )
    print(
        f"robot: solid 4x4x4 hard block, {mech.n_masses} masses, {n_springs} springs, "
        f"{n_steps} steps (duration {duration:g} s, dt {mech.sim.step:g}); "
        f"median of {repeats} runs (single robot: {2 * repeats + 1})\n"
    )

    simulate(mech)  # compile (or load) both kernels before timing
    simulate_batch(batch[:2])
    print(f"  {'spring updates per second (M/s)':<44}{'per core':>12}{'total':>12}{'wall s':>10}")
    one_step = n_springs * n_steps
    seconds = median_seconds(lambda: simulate(mech)[0], 2 * repeats + 1, "one")  # short: more
    single = rate_row("numba simulate, 1 robot", one_step, seconds, 1)
    batch_rates = {}
    for threads in (1, 2):
        run = functools.partial(simulate_batch, batch, threads=threads)
        seconds = median_seconds(run, repeats, f"batch{threads}")
        label = f"numba simulate_batch, {n_batch} robots, {threads} thread{'s' * (threads > 1)}"
        batch_rates[threads] = rate_row(label, one_step * n_batch, seconds, threads)

    np_rates = {}
    for robots, steps in zip((1, n_batch), numpy_steps, strict=True):
        seconds = median_seconds(lambda r=robots, s=steps: numpy_simulate([mech] * r, s), repeats)
        label = f"NumPy, {robots} robot{'s' * (robots > 1)} ({steps} steps)"
        np_rates[robots] = rate_row(label, n_springs * steps * robots, seconds, 1)

    if not args.quick:
        print(
            f"\n  simulate_batch, {n_batch} robots, 1 thread, by lanes (DEFAULT_LANES: "
            "core/physics/simulate.py)"
        )
        for lanes in (4, 8, 16, 32):
            seconds = median_seconds(lambda n=lanes: simulate_batch(batch, lanes=n), 3)
            rate_row(f"lanes = {lanes}", one_step * n_batch, seconds, 1)

    terrains = terrain_rates(duration, repeats, n_batch)
    moving = terrain_rates(duration, repeats, n_batch, actuated=True)
    print(f"\n  simulate_batch, {n_batch} robots, 1 thread, on each task's terrain (interleaved)")
    print(
        f"  {'terrain':<20}{'blocks M/s':>12}{'/ flat':>8}{'random actuated M/s':>24}{'/ flat':>8}"
    )
    for name, rate in terrains.items():
        print(
            f"  {name:<20}{rate / 1e6:>12.0f}{rate / terrains['flat']:>8.2f}"
            f"{moving[name] / 1e6:>24.0f}{moving[name] / moving['flat']:>8.2f}"
        )

    print("\n  ratios (per core, batch on 1 thread)")
    print(f"  {'numba single / NumPy 1 robot':<44}{single / np_rates[1]:>12.1f}")
    print(f"  {'numba batch / NumPy 1 robot':<44}{batch_rates[1] / np_rates[1]:>12.1f}")
    print(f"  {'numba batch / NumPy 32 robots':<44}{batch_rates[1] / np_rates[n_batch]:>12.1f}")
    print(f"  {'numba batch / numba single':<44}{batch_rates[1] / single:>12.2f}")
    print(f"  {'2 threads / 1 thread (total)':<44}{2 * batch_rates[2] / batch_rates[1]:>12.2f}")

    alone = LAST["one"].final_positions.tobytes()
    same = all(r.final_positions.tobytes() == alone for r in LAST["batch1"] + LAST["batch2"])
    print(f"\n  batch positions bit-identical to simulate: {'yes' if same else 'NO'}")
    # Same physics: the NumPy run agrees with the kernel to rounding.
    short = solid_block(0.1)
    kernel_end = simulate(short)[0].final_positions
    numpy_end = numpy_simulate([short], short.sim.n_steps)[0]
    diff = float(np.abs(kernel_end - numpy_end).max())
    print(f"  NumPy vs kernel after {short.sim.n_steps} steps: max |dx| = {diff:.1e} m")

    with tempfile.TemporaryDirectory(prefix="numba-cache-") as cache_dir:
        cold = first_call(cache_dir)
        files = sorted(p.suffix for p in Path(cache_dir).rglob("*") if p.suffix in (".nbi", ".nbc"))
        warm = first_call(cache_dir)
    print("\n  first call in a fresh process (s)           import  simulate  batch  cache hit/miss")
    for label, run in (("empty numba cache (compiles)", cold), ("warm cache (loads)", warm)):
        print(
            f"  {label:<40}{run['import']:>9.2f}{run['simulate']:>10.2f}"
            f"{run['simulate_batch']:>7.2f}{run['hits']:>8}/{run['misses']}"
        )
    print(f"  cache files written: {files.count('.nbi')} index, {files.count('.nbc')} data")

    recompiled = warm["misses"] > 0 or warm["hits"] < 2
    checks = [
        ("batch >= 300 M/s per core (1 thread)", batch_rates[1] >= TARGETS["batch_per_core"]),
        ("single >= 150 M/s", single >= TARGETS["single"]),
        (">= 30x NumPy (batch vs NumPy 1 robot)", batch_rates[1] / np_rates[1] >= 30),
        (">= 30x NumPy (batch vs NumPy 32 robots)", batch_rates[1] / np_rates[n_batch] >= 30),
        ("warm start loads from cache, no recompile", not recompiled),
        ("every terrain >= 80 % of flat", min(terrains.values()) >= 0.8 * terrains["flat"]),
    ]
    print("\n  targets")
    for label, met in checks:
        print(f"  {label:<44}{'met' if met else 'NOT met':>12}")


if __name__ == "__main__":
    main()
