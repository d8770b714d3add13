"""Robot files served as other tools' formats (`?format=vxa|glb|stl` on a run's best robot and
on any individual): the bytes of the file, its media type and a download name.

Written in the request's thread (the routes are plain `def`, so FastAPI runs them in its
threadpool): a mesh of at most MAX_VOXELS voxels takes milliseconds, and no physics is loaded.
"""

from __future__ import annotations

from typing import Annotated, Any, Literal

from fastapi import Query, Response
from fastapi.exceptions import RequestValidationError

from softevo.core.outputs.export import MEDIA_TYPES, ExportError, export_robot
from softevo.core.robots.robot import Robot

ExportFormat = Literal["vxa", "glb", "stl"]  # softevo.core.outputs.export.FORMATS (a test checks)

FormatQuery = Annotated[
    ExportFormat | None,
    Query(
        description=(
            "return the robot as a file instead of JSON: vxa (Voxelyze / VoxCAD / voxcraft-sim "
            "XML, voxel robots only; evosoro's Voxelyze runs it as it is), glb (glTF 2.0 binary "
            "of the voxel surface, coloured by material) or stl (the voxel surface); "
            "docs/export.md"
        )
    ),
]
#: The 200 answers a `format` adds to a route's OpenAPI entry.
FILE_CONTENT: dict[int | str, dict[str, Any]] = {
    200: {
        "content": {
            media: {"schema": {"type": "string", "format": "binary"}}
            for media in MEDIA_TYPES.values()
        },
        "description": "The robot file as JSON, or with `format` the file in that format",
    }
}


def file_response(robot: Robot, format: ExportFormat, name: str) -> Response:
    """`robot` written as `format`, downloaded as `name`.`format`; 422 if it cannot be."""
    try:
        data = export_robot(robot, format)
    except ExportError as error:
        problem = {"loc": ("query", "format"), "msg": str(error), "type": "value_error"}
        raise RequestValidationError([problem]) from None
    return Response(
        data,
        media_type=MEDIA_TYPES[format],
        headers={"Content-Disposition": f'attachment; filename="{name}.{format}"'},
    )
