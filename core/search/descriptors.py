"""The descriptor catalogue of quality-diversity runs: numbers that say what kind of body a robot
is, each in a fixed range, so MAP-Elites can keep the best robot of every kind.

Every descriptor is computed from the body that is simulated: the largest face-connected group
of the robot's filled voxels (what `softevo.core.robots.lattice` builds; cut-off voxels do not
count).

* `voxels`: filled fraction of the bounding box, in [0, 1];
* `actuated`: actuated (sine or neg_sine) fraction of the filled voxels, in [0, 1];
* `soft`: soft fraction of the filled voxels, in [0, 1];
* `height`: vertical extent of the body relative to the box's height, in [0, 1].

They need voxel labels, so they are defined for the voxel encodings (`voxel`, `voxel-phase`)
and for `cppn` (the labels of its decoded body).

One is behavioural, measured by the simulation rather than read from the body:

* `heading`: the direction of the centre of mass's net horizontal displacement from settle
  time to the end (`SimResult.heading`), degrees counter-clockwise from +x (90: +y), in
  [-180, 180]; 0 for a robot that did not move at all.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from functools import lru_cache
from itertools import compress

from softevo.core.robots.robot import LABELS

#: Label indices of the voxel encoding's genes (`softevo.core.robots.robot.LABELS`).
_EMPTY, _SOFT = LABELS.index("empty"), LABELS.index("soft")
_ACTUATED = (LABELS.index("sine"), LABELS.index("neg_sine"))


#: A label index to the binary digit of "filled" ("0" for empty), and a digit to its value.
_FILLED_DIGIT = bytes(ord("0") if i == _EMPTY else ord("1") for i in range(256))
_DIGIT_VALUE = bytes.maketrans(b"01", b"\x00\x01")


@dataclass(frozen=True)
class Body:
    """The simulated body of a voxel genome: its label of every kept voxel, and its z extent."""

    box: tuple[int, int, int]
    labels: tuple[int, ...]  # the label index of every kept (simulated) voxel
    z_extent: int  # layers the kept voxels span


@dataclass(frozen=True)
class Descriptor:
    name: str
    low: float
    high: float
    describe: Callable[[Body], float] | None  # None: measured by the simulation (`MEASURED`)
    help: str  # says the unit where there is one (axis labels are "name: help")


def _fraction(body: Body, labels: tuple[int, ...]) -> float:
    return sum(body.labels.count(label) for label in labels) / len(body.labels)


CATALOGUE: dict[str, Descriptor] = {
    d.name: d
    for d in (
        Descriptor(
            "voxels",
            0.0,
            1.0,
            lambda b: len(b.labels) / (b.box[0] * b.box[1] * b.box[2]),
            "filled fraction of the bounding box",
        ),
        Descriptor(
            "actuated",
            0.0,
            1.0,
            lambda b: _fraction(b, _ACTUATED),
            "actuated (sine, neg_sine) fraction of the filled voxels",
        ),
        Descriptor(
            "soft", 0.0, 1.0, lambda b: _fraction(b, (_SOFT,)), "soft fraction of the filled voxels"
        ),
        Descriptor(
            "height",
            0.0,
            1.0,
            lambda b: b.z_extent / b.box[2],
            "vertical extent of the body relative to the box's height",
        ),
        Descriptor(
            "heading", -180.0, 180.0, None, "direction of travel (degrees, 0 = +x, 90 = +y)"
        ),
    )
}

#: The behavioural descriptors: measured by the simulation (each a `SimResult` attribute).
MEASURED = frozenset(name for name, d in CATALOGUE.items() if d.describe is None)


def body(labels: Sequence[int], box: tuple[int, int, int]) -> Body | None:
    """The body a voxel genome's labels build (None: no voxel filled, nothing to simulate)."""
    layer = box[0] * box[1]
    # the bit masks are made by bytes and int operations, not a Python loop over the voxels:
    # this runs for every robot a quality-diversity run breeds
    filled = int(bytes(labels)[::-1].translate(_FILLED_DIGIT), 2) if len(labels) else 0
    kept = largest_group(filled, box)
    if not kept:
        return None
    first, last = (kept & -kept).bit_length() - 1, kept.bit_length() - 1
    selected = bin(kept)[:1:-1].encode().translate(_DIGIT_VALUE)  # byte i: voxel i is kept
    z_extent = last // layer - first // layer + 1
    return Body(box, tuple(compress(labels, selected)), z_extent)


def largest_group(filled: int, box: tuple[int, int, int]) -> int:
    """The largest face-connected group of the voxels set in the bit mask `filled` (bit i: voxel
    i, x fastest), ties to the group holding the lowest voxel: `lattice.largest_component`'s
    rule, flood-filled with whole-mask shifts (a few microseconds for the paper's boxes)."""
    nx, layer = box[0], box[0] * box[1]
    everything, not_last_x, not_first_x, not_last_y, not_first_y = _masks(box)
    best, best_size, left = 0, 0, filled
    while left:
        group = left & -left  # the lowest voxel not yet in a group
        while True:
            grown = (
                group
                | (
                    ((group & not_last_x) << 1)
                    | ((group & not_first_x) >> 1)
                    | ((group & not_last_y) << nx)
                    | ((group & not_first_y) >> nx)
                    | (group << layer)
                    | (group >> layer)
                )
                & everything
                & filled
            )
            if grown == group:
                break
            group = grown
        size = group.bit_count()
        if size > best_size:
            best, best_size = group, size
        left &= ~group
    return best


@lru_cache(maxsize=64)
def _masks(box: tuple[int, int, int]) -> tuple[int, int, int, int, int]:
    """All voxels, then those that may step +x, -x, +y, -y without leaving the box."""
    nx, ny, nz = box
    cells = range(nx * ny * nz)
    return (
        (1 << len(cells)) - 1,
        sum(1 << i for i in cells if i % nx != nx - 1),
        sum(1 << i for i in cells if i % nx != 0),
        sum(1 << i for i in cells if (i // nx) % ny != ny - 1),
        sum(1 << i for i in cells if (i // nx) % ny != 0),
    )


def describe(
    names: Sequence[str],
    labels: Sequence[int],
    box: tuple[int, int, int],
    measured: Mapping[str, float] | None = None,
) -> tuple:
    """The descriptor values (in `names`' order) of a voxel genome, the behavioural ones taken
    from `measured` (name -> value); () if it builds nothing or a measured value is missing or
    NaN (a robot whose behaviour is unknown has no cell)."""
    built = body(labels, box)
    if built is None:
        return ()
    values = []
    for name in names:
        describe_body = CATALOGUE[name].describe
        if describe_body is None:
            value = (measured or {}).get(name, math.nan)
            if math.isnan(value):
                return ()
        else:
            value = describe_body(built)
        values.append(float(value))
    return tuple(values)
