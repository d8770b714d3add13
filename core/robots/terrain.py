"""Terrain: the ground a robot moves on, as a simulation setting (`sim.terrain`).

Every kind is a solid below a surface; a mass inside it is pushed out along the surface normal
by the same penalty spring and held by the same Coulomb friction as on the flat ground (the
kernels' `_contact_pass`, docs/physics.md "Terrain"). The surface is a function of x and y only and
every kind is invariant along y except `rough`:

* `flat`: z = 0 (the paper's ground; the default, and the kernels' original arithmetic);
* `slope`: a plane through the origin rising along +x at `angle_deg`;
* `steps`: stairs rising along +x, the first riser at x = `depth`, each `height` higher;
* `rough`: a smooth random height field (a sum of cosines whose directions and phases come from
  `seed` through NumPy's PCG64, so the same seed gives the same field on every machine);
* `hurdles`: bars `height` high and `width` long across the path, the first at x = `spacing`
  and then every `spacing`.

`kernel_params` packs a terrain into the kernels' (kind code, float64 parameters); `surface(x, y)`
evaluates the surface in NumPy (for placing a robot above it, drawing it and the reference).
"""

from __future__ import annotations

import math
from functools import lru_cache
from typing import Annotated, Any, Literal

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, model_validator

from softevo.core.limits import MIN_TERRAIN_LENGTH

#: Kind codes the kernels branch on (FLAT keeps the flat ground's original arithmetic).
FLAT, SLOPE, STEPS, ROUGH, HURDLES = 0, 1, 2, 3, 4
#: Cosines summed by a rough terrain.
ROUGH_WAVES = 8
#: Most heights one drawn mesh of a terrain holds (`mesh`): about 1 MB of JSON.
MAX_MESH_POINTS = 100_000

# Cody-Waite pi / 2 in two parts (the first with 33 significant bits, so q x it is exact) and the
# minimax coefficients of sin and cos on [-pi / 4, pi / 4] (fdlibm's k_sin.c and k_cos.c).
_PIO2_HI, _PIO2_LO = 1.57079632673412561417e00, 6.07710050650619224932e-11
_SIN = (
    -1.66666666666666324348e-01,
    8.33333333332248946124e-03,
    -1.98412698298579493134e-04,
    2.75573137070700676789e-06,
    -2.50507602534068634195e-08,
    1.58969099521155010221e-10,
)
_COS = (
    4.16666666666666019037e-02,
    -1.38888888888741095749e-03,
    2.48015872894767294178e-05,
    -2.75573143513906633035e-07,
    2.08757232129817482790e-09,
    -1.13596475577881948265e-11,
)


def sincos(angle: Any) -> tuple[Any, Any]:  # a float in the kernels, an array in NumPy
    """sin and cos of `angle` (rad) within 2 ulp (1e-20 at the zeros), in plain IEEE arithmetic
    without branches or library calls: the same bits in NumPy and in the kernels (which compile
    this function) on every machine, where libm's may differ by an ulp, and a loop of it
    vectorises. For |angle| below 1e6; a rough field's angles are a few hundred radians."""
    q = np.floor(angle * (2.0 / math.pi) + 0.5)  # nearest multiple of pi / 2
    r = (angle - q * _PIO2_HI) - q * _PIO2_LO
    r2 = r * r
    s1, s2, s3, s4, s5, s6 = _SIN
    c1, c2, c3, c4, c5, c6 = _COS
    sin_r = r + r * r2 * (s1 + r2 * (s2 + r2 * (s3 + r2 * (s4 + r2 * (s5 + r2 * s6)))))
    cos_r = (
        1.0 - 0.5 * r2 + r2 * r2 * (c1 + r2 * (c2 + r2 * (c3 + r2 * (c4 + r2 * (c5 + r2 * c6)))))
    )
    # Turn (sin_r, cos_r) by q quarter turns: an odd q swaps them, q mod 4 in {2, 3} negates
    # sin. Products with 0, 1 or -1 and sums with 0 are exact, so this picks the bits.
    half = np.floor(q * 0.5)
    odd = q - 2.0 * half
    even = 1.0 - odd
    sign = 1.0 - 2.0 * (half - 2.0 * np.floor(q * 0.25))
    sin_a = sign * (sin_r * even + cos_r * odd)
    cos_a = (sign * even - sign * odd) * (cos_r * even + sin_r * odd)
    return sin_a, cos_a


_MODEL = ConfigDict(extra="forbid", frozen=True, strict=True, allow_inf_nan=False)


class Flat(BaseModel):
    model_config = _MODEL
    kind: Literal["flat"] = "flat"

    @property
    def code(self) -> int:
        return FLAT

    def params(self) -> list[float]:
        return [0.0]

    def surface(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        return np.zeros(np.broadcast(x, y).shape)


class Slope(BaseModel):
    model_config = _MODEL
    kind: Literal["slope"] = "slope"
    angle_deg: float = Field(
        description="rise along +x (degrees; negative: downhill)", ge=-60, le=60
    )

    @property
    def code(self) -> int:
        return SLOPE

    def params(self) -> list[float]:
        angle = math.radians(self.angle_deg)
        return [math.tan(angle), math.cos(angle), math.sin(angle)]

    def surface(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        return np.broadcast_to(
            np.asarray(x, dtype=float) * math.tan(math.radians(self.angle_deg)),
            np.broadcast(x, y).shape,
        ).copy()


class Steps(BaseModel):
    model_config = _MODEL
    kind: Literal["steps"] = "steps"
    height: float = Field(0.2, description="rise of each step (m)", gt=0, le=100)
    depth: float = Field(
        4.15, description="tread of each step along x (m)", ge=MIN_TERRAIN_LENGTH, le=1000
    )

    @property
    def code(self) -> int:
        return STEPS

    def params(self) -> list[float]:
        return [self.height, self.depth]

    def surface(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        index = np.maximum(np.floor(np.asarray(x, dtype=float) / self.depth), 0.0)
        return np.broadcast_to(index * self.height, np.broadcast(x, y).shape).copy()


class Rough(BaseModel):
    model_config = _MODEL
    kind: Literal["rough"] = "rough"
    amplitude: float = Field(
        0.2, description="largest height above or below z = 0 (m)", gt=0, le=100
    )
    wavelength: float = Field(
        3.0, description="wavelength of the field's cosines (m)", ge=MIN_TERRAIN_LENGTH, le=1000
    )
    seed: int = Field(0, ge=0, le=2**32 - 1, description="the field's random directions, phases")

    @property
    def code(self) -> int:
        return ROUGH

    def waves(self) -> np.ndarray:
        """[ROUGH_WAVES, 4]: wave vector (kx, ky) (rad/m), phase (rad), weight (m)."""
        return _waves(self.amplitude, self.wavelength, self.seed)

    def params(self) -> list[float]:
        """The highest the field reaches (sum of |weights|: masses above skip the cosines),
        then the waves row by row."""
        waves = self.waves()
        return [float(np.abs(waves[:, 3]).sum()), *waves.ravel().tolist()]

    def surface(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        x, y = np.broadcast_arrays(np.asarray(x, dtype=float), np.asarray(y, dtype=float))
        total = np.zeros(x.shape)
        for kx, ky, phase, weight in self.waves().tolist():  # the kernels' order of summation
            total = total + weight * sincos(kx * x + ky * y + phase)[1]
        return total


@lru_cache(maxsize=64)
def _waves(amplitude: float, wavelength: float, seed: int) -> np.ndarray:
    rng = np.random.Generator(np.random.PCG64(seed))
    angle = rng.uniform(0.0, 2.0 * math.pi, ROUGH_WAVES)
    phase = rng.uniform(0.0, 2.0 * math.pi, ROUGH_WAVES)
    wavenumber = 2.0 * math.pi / wavelength
    weight = np.full(ROUGH_WAVES, amplitude / ROUGH_WAVES)
    sin_angle, cos_angle = sincos(angle)  # not NumPy's, whose SIMD paths differ between CPUs
    waves = np.stack([wavenumber * cos_angle, wavenumber * sin_angle, phase, weight], 1)
    waves.flags.writeable = False
    return waves


class Hurdles(BaseModel):
    model_config = _MODEL
    kind: Literal["hurdles"] = "hurdles"
    height: float = Field(0.15, description="height of each bar (m)", gt=0, le=100)
    spacing: float = Field(
        4.15, description="distance between bars' front faces (m)", ge=MIN_TERRAIN_LENGTH, le=1000
    )
    width: float = Field(
        0.5, description="length of each bar along x (m)", ge=MIN_TERRAIN_LENGTH, le=1000
    )

    @model_validator(mode="after")
    def _gaps(self) -> Hurdles:
        if self.width >= self.spacing:
            raise ValueError(
                f"width: a bar ({self.width} m) must be shorter than the spacing "
                f"({self.spacing} m), or there is no ground between bars"
            )
        return self

    @property
    def code(self) -> int:
        return HURDLES

    def params(self) -> list[float]:
        return [self.height, self.spacing, self.width]

    def surface(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        x = np.asarray(x, dtype=float)
        index = np.floor(x / self.spacing)
        on_bar = (index >= 1) & (x - index * self.spacing <= self.width)
        return np.broadcast_to(np.where(on_bar, self.height, 0.0), np.broadcast(x, y).shape).copy()


AnyTerrain = Flat | Slope | Steps | Rough | Hurdles
Terrain = Annotated[AnyTerrain, Field(discriminator="kind")]


#: How far ahead of a robot's front face (the largest x of its masses at rest) the first riser
#: of `steps` or bar of `hurdles` stands at the start (m), whatever the robot's size.
FIRST_FEATURE_GAP = 0.15


def start_shift(terrain: AnyTerrain, front: float) -> float:
    """How far along x to move a robot whose front face is at x = `front` (m), so that the first
    riser or bar stands FIRST_FEATURE_GAP ahead of it: features are placed relative to the
    robot, so a 3x3x3 box meets them as a 4x4x4 one does (they stood at x = depth or spacing
    whatever the box, and small boxes never reached them). 0 for the other kinds."""
    if isinstance(terrain, Steps):
        return terrain.depth - FIRST_FEATURE_GAP - front
    if isinstance(terrain, Hurdles):
        return terrain.spacing - FIRST_FEATURE_GAP - front
    return 0.0


def kernel_params(terrain: AnyTerrain) -> tuple[int, np.ndarray]:
    """The kernels' terrain arguments: kind code and a float64 parameter array."""
    return terrain.code, np.array(terrain.params(), dtype=np.float64)


def edge_count(terrain: AnyTerrain, low: float, high: float) -> int:
    """How many x `edges` would return between `low` and `high`, counted without listing them
    (a tread of 1e-9 m puts billions of risers under a robot's path)."""
    if isinstance(terrain, Steps):
        first = max(1, math.ceil(low / terrain.depth))
        return max(0, math.floor(high / terrain.depth) - first + 1)
    if isinstance(terrain, Hurdles):
        first = max(1, math.floor(low / terrain.spacing))
        return 2 * max(0, math.floor(high / terrain.spacing) - first + 1)
    return 0


def edges(terrain: AnyTerrain, low: float, high: float) -> list[float]:
    """x of the vertical faces (risers, bar faces) between `low` and `high`."""
    if isinstance(terrain, Steps):
        first = max(1, math.ceil(low / terrain.depth))
        return [i * terrain.depth for i in range(first, math.floor(high / terrain.depth) + 1)]
    if isinstance(terrain, Hurdles):
        first = max(1, math.floor(low / terrain.spacing))
        bars = range(first, math.floor(high / terrain.spacing) + 1)
        return [x for i in bars for x in (i * terrain.spacing, i * terrain.spacing + terrain.width)]
    return []


def mesh(
    terrain: AnyTerrain,
    x_range: tuple[float, float],
    y_range: tuple[float, float],
    step: float,
    most: int = MAX_MESH_POINTS,
) -> dict[str, list]:
    """The surface over a rectangle as a height grid for a viewer: x (m) every `step` and on
    both sides of every vertical face (so risers and bars are drawn upright), y every `step`
    (two rows for the kinds that do not vary along y), z [len(y)][len(x)] (m, 3 decimals).

    At most `most` heights whatever the terrain and the rectangle (as a replay's positions are
    capped): the grid coarsens until it fits, and faces too many to draw upright within it
    are left to the grid."""
    (x0, x1), (y0, y1) = x_range, y_range
    rough = isinstance(terrain, Rough)

    def rows(step: float) -> int:  # len(y), or a bound of it
        return math.ceil((y1 - y0) / step) + 2 if rough else 2

    def columns(step: float) -> int:  # a bound of len(x) on the grid alone
        return math.ceil((x1 - x0) / step) + 2

    while columns(step) * rows(step) > most:
        step *= 1.25
    xs = set(np.arange(x0, x1 + step, step).round(6).tolist())
    faces = edge_count(terrain, x0, x1)  # each drawn with two columns
    if (columns(step) + 2 * faces) * rows(step) <= most:
        for face in edges(terrain, x0, x1):  # just before a face, and on it: it is upright
            xs.update((round(face - 1e-6, 7), face))
    x = np.array(sorted(xs))
    y = np.arange(y0, y1 + step, step) if rough else np.array([y0, y1])
    z = terrain.surface(x[None, :], y[:, None])
    return {"x": x.round(6).tolist(), "y": y.round(6).tolist(), "z": z.round(3).tolist()}
