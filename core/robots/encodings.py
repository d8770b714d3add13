"""Encodings: how a genome's genes become a robot, and back.

* `voxel` (paper phase 3): one label per voxel of the bounding box (empty, soft, hard, sine,
  neg_sine) and the actuation genes a, b, c.
* `voxel-phase` (co-design): `voxel` where every voxel also carries its own actuation phase and
  amplitude, so the gait evolves with the body; the paper's sine / neg_sine are phases 0 and pi.
* `cube-springs` (paper phase 2): one cube; each of its 28 springs picks one of a few [k, b, w, c]
  options.
* `spring` (beyond the paper, its stated future work): which voxels are filled, plus one material
  label (soft, hard, sine, neg_sine) for every spring of the bounding-box lattice, and a, b, c.
  Modules are single springs, not whole cubes.
* `cppn` (the field's indirect encoding): a network queried at every voxel, decoded into a
  `voxel-phase` robot (`softevo.core.robots.cppn_encoding`, with its own NEAT variation).

Each is found by name in the entry-point group `softevo.encodings`
(`softevo.core.robots.encoding_registry`), so a user's encoding is one module of its own: an
`Encoding` subclass (genome, random, decode to a robot) that may bring its own `Variation`
(mate, mutate) and its own reading of diversity; search reads encodings through this interface
alone.

Every encoding exposes its genes to the operators as *segments*: runs of discrete genes with an
alphabet size each (crossover cuts each segment separately, so the occupancy of the `spring`
encoding never swaps with spring labels), and bounded real genes.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property
from typing import ClassVar, Protocol

import numpy as np

from softevo.core.robots.genome import Genome, gene_diversity
from softevo.core.robots.lattice import full_lattice
from softevo.core.robots.robot import (
    GENE_BOUNDS,
    LABELS,
    SPRING_LABELS,
    Actuation,
    LabelledSpringRobot,
    Robot,
    SpringRobot,
    VoxelRobot,
)
from softevo.core.robots.settings import SimSettings

#: The paper's phase 2 options [k, b, w, c]; it prints the third twice, we read the fourth as
#: its negative-phase twin.
PAPER_CUBE_OPTIONS = (
    (1000.0, 0.0, 1.0, 0.0),
    (2000.0, 0.0, 1.0, 0.0),
    (5000.0, 0.05, 1.0, 0.0),
    (5000.0, -0.05, 1.0, 0.0),
)
#: Spring options [k, b, w, c] of the `cube-springs` encoding.
CubeOptions = tuple[tuple[float, float, float, float], ...]
ACTUATION_BOUNDS = np.array([GENE_BOUNDS["a"], GENE_BOUNDS["b"], GENE_BOUNDS["c"]])


class EncodingError(ValueError):
    """A robot that this encoding cannot express."""


@dataclass(frozen=True)
class Segment:
    """A run of discrete genes [start, stop) whose values are 0 .. alphabet - 1."""

    start: int
    stop: int
    alphabet: int


class Rates(Protocol):
    """The variation settings of a run that an encoding's own operators read (the search
    settings, `softevo.core.search.settings.SearchSettings`, have them)."""

    @property
    def crossover_probability(self) -> float: ...
    @property
    def mutation_probability(self) -> float: ...
    @property
    def mutation_genes(self) -> int: ...
    @property
    def mutation_sigma(self) -> float: ...


class Variation(ABC):
    """Operators an encoding brings of its own (`cppn`: NEAT), which the strategies use in
    place of their segment-wise crossover and mutation; every draw from `rng`."""

    @abstractmethod
    def mate(
        self, rates: Rates, first: Genome, second: Genome, rng: np.random.Generator
    ) -> tuple[bool, list[tuple[Genome, str]]]:
        """Whether the pair was crossed, and two children with their operator labels."""

    @abstractmethod
    def mutate(self, rates: Rates, genome: Genome, rng: np.random.Generator) -> Genome:
        """A mutated copy of `genome`."""


class Encoding(ABC):
    """Genes <-> robots. Subclasses define the segments, real-gene bounds and the mapping."""

    name: str
    segments: tuple[Segment, ...]
    real_bounds: np.ndarray  # [R, 2] low, high
    shape: tuple[int, int, int]
    #: Real genes that belong to the robot as a whole come first; then `voxel_reals` blocks of
    #: one real gene per voxel, which crossover cuts where it cuts the labels (co-design).
    voxel_reals: int = 0
    #: Operators of its own (None: the strategies' segment-wise crossover and mutation).
    variation: ClassVar[Variation | None] = None
    #: Whether `labels` gives one label per voxel of `shape` (what the descriptors read).
    describable: ClassVar[bool] = False

    @classmethod
    def build(cls, shape: tuple[int, int, int], cube_options: CubeOptions) -> Encoding:
        """This encoding for a run's bounding box (and cube options, which only one reads)."""
        return cls(shape)  # type: ignore[call-arg]  # every subclass but one takes the shape

    def diversity(self, genomes: list[Genome]) -> float:
        """A generation's diversity (the curve's column): by default how much the discrete
        genes differ (`gene_diversity`)."""
        return gene_diversity(genomes)

    @property
    def n_discrete(self) -> int:
        return self.segments[-1].stop

    @cached_property
    def alphabet(self) -> np.ndarray:
        """Alphabet size of every discrete gene, int array [n_discrete] (read-only: built once,
        since breeding asks for it for every child)."""
        sizes = np.empty(self.n_discrete, dtype=np.int64)
        for segment in self.segments:
            sizes[segment.start : segment.stop] = segment.alphabet
        sizes.setflags(write=False)
        return sizes

    def random(self, rng: np.random.Generator) -> Genome:
        """A uniformly random genome (the initial population and random immigrants)."""
        discrete = rng.integers(0, self.alphabet)
        low, high = self.real_bounds.T
        real = rng.uniform(low, high) if len(self.real_bounds) else np.empty(0)
        return self.genome(discrete, real)

    def genome(
        self, discrete: Sequence[int] | np.ndarray, real: Sequence[float] | np.ndarray
    ) -> Genome:
        """Genes as Python ints and floats (`tolist` gives exactly `int(g)` and `float(g)`)."""
        return Genome(
            self.name,
            tuple(np.asarray(discrete, dtype=np.int64).tolist()),
            tuple(np.asarray(real, dtype=np.float64).tolist()),
        )

    def check(self, genome: Genome) -> None:
        """Refuse a genome of another encoding, the wrong length or out-of-range genes."""
        if genome.encoding != self.name:
            raise EncodingError(f"genome of encoding {genome.encoding!r}, expected {self.name!r}")
        discrete = genome.discrete
        if len(discrete) != self.n_discrete or len(genome.real) != len(self.real_bounds):
            raise EncodingError(
                f"{self.name} genome needs {self.n_discrete} discrete and "
                f"{len(self.real_bounds)} real genes, got {len(discrete)} and {len(genome.real)}"
            )
        for segment in self.segments:  # plain min and max: every robot file pays for this check
            part = discrete[segment.start : segment.stop]
            if len(part) and (min(part) < 0 or max(part) >= segment.alphabet):
                raise EncodingError(f"{self.name} genome has a discrete gene out of its alphabet")

    def labels(self, genome: Genome) -> tuple[int, ...]:
        """Label index of every voxel of the genome's body (what the descriptors read): the
        voxel encodings' discrete genes themselves."""
        return genome.discrete

    def check_stored(self, genome: Genome) -> None:
        """Refuse, as `check` does, a genome read from a file, and one whose real genes are
        outside their bounds (which no operator of this encoding makes)."""
        self.check(genome)
        bounds = self.real_bounds_of(genome).tolist()
        for value, (low, high) in zip(genome.real, bounds, strict=True):
            if not low <= value <= high:
                raise EncodingError(f"real: {value!r} is outside its bounds [{low:g}, {high:g}]")

    def real_bounds_of(self, genome: Genome) -> np.ndarray:
        """Bounds of `genome`'s real genes (an encoding of variable length says per genome)."""
        return self.real_bounds

    @abstractmethod
    def to_robot(self, genome: Genome, sim: SimSettings) -> Robot:
        """The robot a genome describes."""

    @abstractmethod
    def from_robot(self, robot: Robot) -> Genome:
        """The genome of a robot this encoding made (inverse of `to_robot`)."""


def _actuation(real: tuple[float, ...]) -> Actuation:
    return Actuation(*real)


def _actuation_genes(robot: VoxelRobot | LabelledSpringRobot) -> tuple[float, float, float]:
    return (robot.actuation.a, robot.actuation.b, robot.actuation.c)


def _index(values: tuple, allowed: tuple, what: str) -> list[int]:
    try:
        return [allowed.index(v) for v in values]
    except ValueError:
        bad = next(v for v in values if v not in allowed)
        raise EncodingError(f"{what} {bad!r} is not one of {allowed}") from None


class VoxelEncoding(Encoding):
    name = "voxel"
    describable = True

    def __init__(self, shape: tuple[int, int, int]) -> None:
        self.shape = shape
        self.segments = (Segment(0, math.prod(shape), len(LABELS)),)
        self.real_bounds = ACTUATION_BOUNDS

    def to_robot(self, genome: Genome, sim: SimSettings) -> VoxelRobot:
        self.check(genome)
        labels = tuple(map(LABELS.__getitem__, genome.discrete))
        return VoxelRobot(self.shape, labels, _actuation(genome.real), sim)

    def from_robot(self, robot: Robot) -> Genome:
        if not isinstance(robot, VoxelRobot) or robot.shape != self.shape:
            raise EncodingError(f"not a {'x'.join(map(str, self.shape))} voxel robot")
        if robot.phases is not None or robot.amplitudes is not None:
            raise EncodingError("a robot with per-voxel phases is of the voxel-phase encoding")
        return self.genome(np.array(_index(robot.voxels, LABELS, "label")), _actuation_genes(robot))


class CubeSpringsEncoding(Encoding):
    name = "cube-springs"

    def __init__(self, options: tuple[tuple[float, float, float, float], ...] = PAPER_CUBE_OPTIONS):
        self.shape = (1, 1, 1)
        self.options = tuple(tuple(float(v) for v in option) for option in options)
        self.segments = (Segment(0, 28, len(self.options)),)
        self.real_bounds = np.empty((0, 2))

    @classmethod
    def build(cls, shape: tuple[int, int, int], cube_options: CubeOptions) -> Encoding:
        return cls(cube_options)

    def to_robot(self, genome: Genome, sim: SimSettings) -> SpringRobot:
        self.check(genome)
        springs = np.array([self.options[g] for g in genome.discrete])
        return SpringRobot(self.shape, (True,), springs, sim)

    def from_robot(self, robot: Robot) -> Genome:
        if not isinstance(robot, SpringRobot) or robot.shape != self.shape:
            raise EncodingError("not a one-cube robot with per-spring options")
        rows = tuple(tuple(float(v) for v in row) for row in np.asarray(robot.springs))
        return self.genome(np.array(_index(rows, self.options, "spring option")), ())


#: Bounds of a voxel's own phase (rad) in the `voxel-phase` encoding: one turn.
PHASE_BOUNDS = (-math.pi, math.pi)


class VoxelPhaseEncoding(Encoding):
    """`voxel` with co-designed gaits: the labels, then real genes a and c of the robot, every
    voxel's own amplitude (the paper's b bounds) and every voxel's own phase (one turn). Only
    actuated voxels use theirs; crossover cuts a voxel's amplitude and phase with its label."""

    name = "voxel-phase"
    describable = True
    voxel_reals = 2

    def __init__(self, shape: tuple[int, int, int]) -> None:
        self.shape = shape
        n_voxels = math.prod(shape)
        self.segments = (Segment(0, n_voxels, len(LABELS)),)
        self.real_bounds = np.array(
            [
                GENE_BOUNDS["a"],
                GENE_BOUNDS["c"],
                *[GENE_BOUNDS["b"]] * n_voxels,
                *[PHASE_BOUNDS] * n_voxels,
            ]
        )

    def to_robot(self, genome: Genome, sim: SimSettings) -> VoxelRobot:
        self.check(genome)
        n = self.n_discrete
        a, c = genome.real[:2]
        amplitudes, phases = genome.real[2 : 2 + n], genome.real[2 + n :]
        labels = tuple(map(LABELS.__getitem__, genome.discrete))
        return VoxelRobot(self.shape, labels, Actuation(a, 0.0, c), sim, phases, amplitudes)

    def from_robot(self, robot: Robot) -> Genome:
        """Also of a plain `voxel` robot: phase 0 and the robot's b on every voxel."""
        if not isinstance(robot, VoxelRobot) or robot.shape != self.shape:
            raise EncodingError(f"not a {'x'.join(map(str, self.shape))} voxel robot")
        n = self.n_discrete
        amplitudes = robot.amplitudes or (robot.actuation.b,) * n
        phases = robot.phases or (0.0,) * n
        real = (robot.actuation.a, robot.actuation.c, *amplitudes, *phases)
        return self.genome(np.array(_index(robot.voxels, LABELS, "label")), real)


class SpringEncoding(Encoding):
    """Occupancy genes (0 empty, 1 filled) for the voxels, then one label per lattice spring."""

    name = "spring"

    def __init__(self, shape: tuple[int, int, int]) -> None:
        self.shape = shape
        n_voxels = math.prod(shape)
        n_springs = full_lattice(shape).n_springs
        self.segments = (
            Segment(0, n_voxels, 2),
            Segment(n_voxels, n_voxels + n_springs, len(SPRING_LABELS)),
        )
        self.real_bounds = ACTUATION_BOUNDS

    def random(self, rng: np.random.Generator) -> Genome:
        """Voxels filled with probability 4/5, as in a random `voxel` genome; labels uniform."""
        genome = super().random(rng)
        n_voxels = self.segments[0].stop
        filled = (rng.random(n_voxels) < 0.8).astype(np.int64)
        return self.genome(np.concatenate([filled, genome.discrete[n_voxels:]]), genome.real)

    def to_robot(self, genome: Genome, sim: SimSettings) -> LabelledSpringRobot:
        self.check(genome)
        n_voxels = self.segments[0].stop
        filled = tuple(bool(g) for g in genome.discrete[:n_voxels])
        labels = tuple(SPRING_LABELS[g] for g in genome.discrete[n_voxels:])
        return LabelledSpringRobot(self.shape, filled, labels, _actuation(genome.real), sim)

    def from_robot(self, robot: Robot) -> Genome:
        if not isinstance(robot, LabelledSpringRobot) or robot.shape != self.shape:
            raise EncodingError(f"not a {'x'.join(map(str, self.shape))} spring-labelled robot")
        labels = _index(robot.spring_labels, SPRING_LABELS, "spring label")
        discrete = np.array([*(int(f) for f in robot.filled), *labels])
        return self.genome(discrete, _actuation_genes(robot))
