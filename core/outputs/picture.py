"""Moving pictures of a robot: its simulation as a GIF or MP4, or one frame at rest as a PNG,
drawn offscreen by matplotlib's Agg (no screen, no GPU) (README "Moving pictures").

Every filled voxel is a hexahedron whose 8 corners are its 8 lattice masses at that frame; only
its outer faces are drawn (`softevo.core.outputs.export.surface_faces`, the exporters' own rule),
with Lambert shading from a fixed light, coloured by material as the dashboard does (actuated voxels
of a co-designed robot by the hue of their phase). The camera is orthographic and follows the
centre of mass; the ground or terrain is drawn as a checkerboard, so motion shows against it.
"""

from __future__ import annotations

import io
import math
import shutil
from dataclasses import replace
from typing import Any

import numpy as np

from softevo.core.limits import (
    MAX_PICTURE_FPS,
    MAX_PICTURE_SECONDS,
    MAX_REPLAY_POSITIONS,
    MIN_PICTURE_FPS,
)
from softevo.core.outputs.export import mass_faces
from softevo.core.robots.robot import ACTUATED_LABELS, COLOURS, Robot, VoxelRobot, build_mechanics

PICTURE_FORMATS = ("gif", "mp4")
MEDIA_TYPES = {"gif": "image/gif", "mp4": "video/mp4", "png": "image/png"}
#: Defaults: frames per simulated second, simulated seconds, picture size (pixels).
FPS, SECONDS, SIZE = 12.0, 3.0, (320, 240)
THUMBNAIL_SIZE = (120, 90)
_DPI = 80
#: Camera: looking from azimuth / elevation (degrees); light: a fixed direction (world frame).
_AZIMUTH, _ELEVATION = -60.0, 25.0
_LIGHT = np.array([-0.4, -0.6, 0.9]) / np.linalg.norm([-0.4, -0.6, 0.9])
#: A position farther than this from the origin (m) is drawn as a simulation that blew up.
_FARTHEST = 1e5
_GROUND = ((0.93, 0.93, 0.90), (0.82, 0.83, 0.80))
FFMPEG_MISSING = (
    "MP4 needs the ffmpeg program, which is not on PATH: install it (apt-get install ffmpeg, "
    "brew install ffmpeg) or ask for a .gif"
)


class PictureError(ValueError):
    """A picture that cannot be made as asked; the message is one line."""


def check(fps: float, seconds: float) -> int:
    """The number of frames of `seconds` at `fps`, or PictureError saying which is out of range."""
    if not (math.isfinite(fps) and MIN_PICTURE_FPS <= fps <= MAX_PICTURE_FPS):
        raise PictureError(
            f"fps must be between {MIN_PICTURE_FPS:g} and {MAX_PICTURE_FPS:g}, got {fps:g}"
        )
    if not (math.isfinite(seconds) and 0 < seconds <= MAX_PICTURE_SECONDS):
        raise PictureError(
            f"duration must be > 0 and at most {MAX_PICTURE_SECONDS:g} s, got {seconds:g}"
        )
    return max(1, round(fps * seconds))


def one_period(robot: Robot) -> float:
    """Simulated seconds that show a whole stroke: one actuation period (2 pi / omega), at least
    SECONDS and at most MAX_PICTURE_SECONDS (3 s at 1 rad/s is under half a period: a robot
    that leans forward in it and back after looks like a crawler)."""
    omega = build_mechanics(robot).omega
    period = 2 * math.pi / omega if omega > 0 else SECONDS
    return min(MAX_PICTURE_SECONDS, max(SECONDS, period))


def ffmpeg_available() -> bool:
    return shutil.which("ffmpeg") is not None


def _camera() -> tuple[np.ndarray, np.ndarray]:
    """Screen axes (right, up) and the view direction (towards the viewer) as rows."""
    az, el = math.radians(_AZIMUTH), math.radians(_ELEVATION)
    towards = np.array([math.cos(el) * math.cos(az), math.cos(el) * math.sin(az), math.sin(el)])
    right = np.cross([0.0, 0.0, 1.0], towards)
    right /= np.linalg.norm(right)
    up = np.cross(towards, right)
    return np.stack([right, up]), towards


class _Scene:
    """What stays the same from frame to frame: the outer faces as mass indices, their colours."""

    def __init__(self, robot: Robot) -> None:
        self.robot = robot
        self.mechanics = build_mechanics(robot)
        self.faces, flat, labels = mass_faces(robot, self.mechanics.lattice)  # [F, 4] masses
        self.colours = np.array([COLOURS[str(label)] for label in labels], dtype=float) / 255
        if isinstance(robot, VoxelRobot) and robot.phases is not None:
            from matplotlib.colors import hsv_to_rgb

            phase = np.asarray(robot.phases, dtype=float)[flat] + robot.actuation.c
            phase = phase + np.where(labels == "neg_sine", math.pi, 0.0)  # its minus sign: pi
            hue = np.mod(phase, 2 * math.pi) / (2 * math.pi)
            hsv = np.stack([hue, np.full_like(hue, 0.55), np.full_like(hue, 0.85)], axis=1)
            actuated = np.isin(labels, ACTUATED_LABELS)
            self.colours[actuated] = hsv_to_rgb(hsv)[actuated]
        self.legend = _legend(
            labels, phased=isinstance(robot, VoxelRobot) and robot.phases is not None
        )
        self.axes, self.towards = _camera()
        span = float(np.ptp(self.mechanics.positions, axis=0).max()) or 1.0
        self.span = span
        self.half = 1.1 * span + robot.sim.edge_length  # half the view's width (m): room to move


RGB = tuple[float, float, float]

#: The legend's names of the materials (robot-file labels), in this order.
MATERIAL_NAMES = {
    "soft": "soft",
    "hard": "hard",
    "sine": "actuated (sine)",
    "neg_sine": "actuated (-sine)",
    "filled": "filled",
}


def _legend(labels: np.ndarray, phased: bool) -> list[tuple[str, RGB]]:
    """(name, colour) of each material the robot's drawn faces show, for the picture's legend;
    a co-designed robot's actuated voxels are one entry, their hue being their phase."""
    present = set(np.asarray(labels).tolist())
    entries = []
    for label, name in MATERIAL_NAMES.items():
        if label not in present:
            continue
        if phased and label in ACTUATED_LABELS:
            if label == "sine" or "sine" not in present:
                entries.append(("actuated (hue: phase)", (0.85, 0.55, 0.4)))
            continue
        red, green, blue = COLOURS[label]
        entries.append((name, (red / 255, green / 255, blue / 255)))
    return entries


def _draw(scene: _Scene, ax: Any, positions: np.ndarray, clock: str | None) -> None:
    """One frame on `ax` (cleared): ground, the robot's shaded outer faces, the clock."""
    from matplotlib.collections import PolyCollection

    ax.clear()
    ax.set_axis_off()
    half, aspect = scene.half, SIZE[1] / SIZE[0]
    ax.set_xlim(-half, half)
    ax.set_ylim(-half * aspect, half * aspect)
    (polygons, tiles), (screen, colours) = _polygons(scene, positions)
    # An array [N, 4, 2] takes PolyCollection's fast path; its stub knows only a Sequence
    ax.add_collection(
        PolyCollection(
            polygons,  # type: ignore[arg-type]  # an array [N, 4, 2], as said above
            facecolors=tiles,
            edgecolors="none",
        )
    )
    ax.add_collection(
        PolyCollection(
            screen,  # type: ignore[arg-type]  # an array [N, 4, 2], as above
            facecolors=colours,
            edgecolors=(0, 0, 0, 0.35),
            linewidths=0.4,
        )
    )
    if clock is not None:
        ax.text(0.03, 0.95, clock, transform=ax.transAxes, va="top", fontsize=8)
    if scene.legend and clock is not None:  # a movie's frame (a thumbnail is too small)
        from matplotlib.patches import Patch

        handles = [
            Patch(facecolor=colour, edgecolor=(0, 0, 0, 0.35), label=name)
            for name, colour in scene.legend
        ]
        ax.legend(
            handles=handles,
            loc="lower right",
            fontsize=6,
            frameon=True,
            framealpha=0.8,
            handlelength=1.0,
            borderpad=0.4,
            labelspacing=0.3,
        )


Polygons = tuple[np.ndarray, np.ndarray]


def _polygons(scene: _Scene, positions: np.ndarray) -> tuple[Polygons, Polygons]:
    """A frame's (screen polygons, colours): the ground's tiles, then the robot's visible outer
    faces shaded and ordered back to front."""
    centre = positions.mean(axis=0)
    corners = positions[scene.faces]  # [F, 4, 3]
    normals = np.cross(corners[:, 2] - corners[:, 0], corners[:, 3] - corners[:, 1])
    normals /= np.linalg.norm(normals, axis=1, keepdims=True) + 1e-12
    visible = normals @ scene.towards > 0
    shade = 0.35 + 0.65 * np.clip(normals @ _LIGHT, 0, 1)
    colours = np.clip(scene.colours * shade[:, None], 0, 1)
    relative = corners - centre
    depth = (relative @ scene.towards).mean(axis=1)
    order = np.argsort(depth)
    order = order[visible[order]]
    screen = relative[order] @ scene.axes.T  # [F, 4, 2]
    return _ground(scene, centre), (screen, colours[order])


class _Frames:
    """A movie's frames on one axes: the first drawn whole (`_draw`), each later one by moving
    the ground's and the body's polygons and setting the clock's text, since clearing the axes
    and building them again (ticks, spines, the legend) took half of each frame's time. The
    pixels are the same as a frame drawn whole."""

    def __init__(self, scene: _Scene, ax: Any) -> None:
        self.scene, self.ax = scene, ax
        self.artists: tuple[Any, Any, Any] | None = None

    def draw(self, positions: np.ndarray, clock: str) -> None:
        if self.artists is None:
            _draw(self.scene, self.ax, positions, clock)
            ground, body = self.ax.collections
            (text,) = self.ax.texts
            self.artists = (ground, body, text)
            return
        ground, body, text = self.artists
        (polygons, tiles), (screen, colours) = _polygons(self.scene, positions)
        ground.set_verts(polygons)
        ground.set_facecolor(tiles)
        body.set_verts(screen)
        body.set_facecolor(colours)
        text.set_text(clock)


def _ground(scene: _Scene, centre: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Checkerboard tiles of the ground (or terrain surface) around the centre, in screen space."""
    edge = scene.robot.sim.edge_length
    reach = 2.5 * scene.half
    x0, y0 = math.floor((centre[0] - reach) / edge), math.floor((centre[1] - reach) / edge)
    n = math.ceil(2 * reach / edge) + 1
    i, j = (
        v.ravel() for v in np.meshgrid(np.arange(x0, x0 + n), np.arange(y0, y0 + n), indexing="ij")
    )
    corner = np.array([(0, 0), (1, 0), (1, 1), (0, 1)])
    x = (i[:, None] + corner[None, :, 0]) * edge
    y = (j[:, None] + corner[None, :, 1]) * edge
    z = np.asarray(scene.robot.sim.terrain.surface(x, y), dtype=float) * np.ones_like(x)
    tiles = np.stack([x, y, z], axis=2) - centre  # [T, 4, 3]
    order = np.argsort((tiles @ scene.towards).mean(axis=1))
    normals = np.cross(tiles[:, 2] - tiles[:, 0], tiles[:, 3] - tiles[:, 1])
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    shade = 0.55 + 0.45 * np.clip(normals @ _LIGHT, 0, 1) / max(float(_LIGHT[2]), 1e-9)
    colours = np.clip(np.array(_GROUND)[(i + j) % 2] * shade[:, None], 0, 1)[order]
    return tiles[order] @ scene.axes.T, colours


def _figure(size: tuple[int, int]) -> Any:
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    figure = Figure(figsize=(size[0] / _DPI, size[1] / _DPI), dpi=_DPI)
    FigureCanvasAgg(figure)
    ax = figure.add_axes((0, 0, 1, 1))
    return figure, ax


def thumbnail_png(robot: Robot, size: tuple[int, int] = THUMBNAIL_SIZE) -> bytes:
    """One shaded frame of the robot at rest (no simulation) as PNG bytes of `size` pixels."""
    scene = _Scene(robot)
    scene.half = 0.8 * scene.span + 0.2 * robot.sim.edge_length  # it stays put: fill the frame
    figure, ax = _figure(size)
    _draw(scene, ax, scene.mechanics.positions, None)
    buffer = io.BytesIO()
    figure.savefig(buffer, format="png", dpi=_DPI)
    return buffer.getvalue()


def movie(robot: Robot, format: str, fps: float = FPS, seconds: float = SECONDS) -> bytes:
    """The robot simulated for `seconds` and drawn at `fps`, as GIF or MP4 bytes."""
    import tempfile
    from pathlib import Path

    from matplotlib.animation import FFMpegWriter, PillowWriter

    if format not in PICTURE_FORMATS:
        raise PictureError(f"unknown format {format!r} (formats: {', '.join(PICTURE_FORMATS)})")
    if format == "mp4" and not ffmpeg_available():
        raise PictureError(FFMPEG_MISSING)
    times, frames = _frames(robot, fps, seconds)
    frames, blew_up_at = hold_last_finite(times, frames)
    scene = _Scene(robot)
    figure, ax = _figure(SIZE)
    drawing = _Frames(scene, ax)
    # matplotlib's stubs say int; both writers take a float (12.5 frames a second is allowed)
    writer = (
        PillowWriter(fps=fps)  # type: ignore[arg-type]  # a float fps, as above
        if format == "gif"
        else FFMpegWriter(fps=fps, codec="h264")  # type: ignore[arg-type]  # as above
    )
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / f"picture.{format}"
        with writer.saving(figure, str(path), dpi=_DPI):
            for time, positions in zip(times, frames, strict=True):
                clock = f"t = {time:.2f} s"
                if blew_up_at is not None and time >= blew_up_at:
                    clock += f": the simulation blew up at {blew_up_at:.2f} s (sim.dt too large?)"
                drawing.draw(positions, clock)
                writer.grab_frame()
        return path.read_bytes()


def movie_from_file(robot_file: dict[str, Any], format: str, fps: float, seconds: float) -> bytes:
    """`movie` of a robot file: what the service's replay process is handed (plain JSON in)."""
    from softevo.core.robots.robot_file import parse_robot

    return movie(parse_robot(robot_file), format, fps, seconds)


def hold_last_finite(times: np.ndarray, frames: np.ndarray) -> tuple[np.ndarray, float | None]:
    """Frames [N, M, 3] with every frame from the first non-finite one (or one flung past
    _FARTHEST metres) on replaced by the last
    finite frame, and that first frame's time (s): a robot whose simulation blew up (too large
    a `sim.dt`) is drawn until it did and then held, never NaN handed to the drawing. (None:
    it never blew up.) The first frame is the robot at rest, always finite."""
    with np.errstate(invalid="ignore"):  # NaN compares False: not finite
        finite = (np.abs(frames) < _FARTHEST).all(axis=(1, 2))
    if finite.all():
        return frames, None
    first = max(1, int(np.argmin(finite)))
    held = frames.copy()
    held[first:] = frames[first - 1]
    return held, float(times[first])


def _frames(robot: Robot, fps: float, seconds: float) -> tuple[np.ndarray, np.ndarray]:
    """Times [N] and mass positions [N, M, 3] of the N = fps x seconds frames at i / fps."""
    from softevo.core.physics import simulate

    n_frames = check(fps, seconds)
    sim = robot.sim
    settle = sim.settle_time if sim.settle_time < seconds else 0.0
    sim = sim.model_copy(update={"duration": float(seconds), "settle_time": settle})
    mechanics = replace(build_mechanics(robot), sim=sim)
    if n_frames * mechanics.n_masses > MAX_REPLAY_POSITIONS:
        raise PictureError(f"{n_frames} frames of {mechanics.n_masses} masses is too many")
    per_step = fps * sim.step  # frames per step; one frame for the whole run when it is tiny
    every = sim.n_steps if per_step * sim.n_steps <= 1 else max(1, math.floor(1.0 / per_step))
    _result, trajectory = simulate(mechanics, record_every=every)
    assert trajectory is not None
    wanted = np.arange(n_frames) / fps
    index = np.abs(trajectory.times[None, :] - wanted[:, None]).argmin(axis=1)
    return trajectory.times[index], trajectory.frames[index]


__all__ = [
    "FFMPEG_MISSING",
    "MEDIA_TYPES",
    "PICTURE_FORMATS",
    "PictureError",
    "check",
    "ffmpeg_available",
    "movie",
    "movie_from_file",
    "thumbnail_png",
]
