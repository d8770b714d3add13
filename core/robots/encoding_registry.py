"""Encodings by name, found through the entry-point group `softevo.encodings`.

The built-ins are registered there by softevo's own `pyproject.toml`, exactly as a user's
package registers its own:

    [project.entry-points."softevo.encodings"]
    my-encoding = "my_package.encoding:MyEncoding"

so `"encoding": "my-encoding"` in a run config works in `softevo run`, `POST /runs` and the
library once the package is installed. A name that two packages claim is refused.
"""

from __future__ import annotations

from functools import cache
from importlib.metadata import entry_points
from typing import TypeGuard

from softevo.core.robots.encodings import (
    PAPER_CUBE_OPTIONS,
    CubeOptions,
    Encoding,
    EncodingError,
)

GROUP = "softevo.encodings"


@cache
def encodings() -> dict[str, type[Encoding]]:
    """Every installed encoding by name, in registration order (loaded once per process)."""
    found: dict[str, type[Encoding]] = {}
    for point in entry_points(group=GROUP):
        if point.name in found:
            raise EncodingError(f"encoding {point.name!r}: registered twice in {GROUP}")
        try:
            loaded = point.load()
        except Exception as error:
            raise EncodingError(
                f"encoding {point.name!r}: cannot load {point.value} ({error}; an install "
                "older than its code? pip install --no-deps --no-build-isolation -e .)"
            ) from None
        if not _is_encoding(loaded):
            raise EncodingError(f"encoding {point.name!r}: {point.value} is not an Encoding")
        if loaded.name != point.name:
            raise EncodingError(
                f"encoding {point.name!r}: {point.value} calls itself {loaded.name!r}"
            )
        found[point.name] = loaded
    if not found:
        raise EncodingError(f"no encodings installed in {GROUP}: is softevo installed?")
    return found


def encoding_class(name: str) -> type[Encoding]:
    """The encoding called `name`; EncodingError lists the installed ones otherwise."""
    installed = encodings()
    if name not in installed:
        raise EncodingError(f"unknown encoding {name!r} ({', '.join(installed)})")
    return installed[name]


def make_encoding(
    name: str, shape: tuple[int, int, int], cube_options: CubeOptions = PAPER_CUBE_OPTIONS
) -> Encoding:
    """The encoding called `name` for a bounding box of `shape`."""
    return encoding_class(name).build(shape, cube_options)


def _is_encoding(loaded: object) -> TypeGuard[type[Encoding]]:
    return isinstance(loaded, type) and issubclass(loaded, Encoding)
