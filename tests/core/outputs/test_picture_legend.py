"""A GIF or MP4 frame names the materials its colours stand for (issue 39: no legend)."""

from __future__ import annotations

from pathlib import Path

from softevo.core.outputs import picture
from softevo.core.robots.robot_file import load_robot


def test_a_movie_frame_has_a_legend_of_the_robots_materials(examples: Path) -> None:
    scene = picture._Scene(load_robot(examples / "crawler_4x4x4.json"))
    names = [name for name, _ in scene.legend]
    assert names == ["soft", "hard", "actuated (sine)", "actuated (-sine)"]
    _figure, ax = picture._figure(picture.SIZE)
    picture._draw(scene, ax, scene.mechanics.positions, "t = 0.00 s")
    assert [text.get_text() for text in ax.get_legend().get_texts()] == names
    picture._draw(scene, ax, scene.mechanics.positions, None)  # a thumbnail: none
    assert ax.get_legend() is None


def test_a_movie_frame_moved_into_place_is_the_frame_drawn_whole(examples: Path) -> None:
    """`movie` draws its first frame whole and moves the polygons and the clock for the next
    (no clearing): the next frame's pixels are those of the same frame drawn whole."""
    import numpy as np

    scene = picture._Scene(load_robot(examples / "crawler_4x4x4.json"))
    times, frames = picture._frames(scene.robot, 10.0, 1.0)
    figure, ax = picture._figure(picture.SIZE)
    drawing = picture._Frames(scene, ax)
    drawing.draw(frames[0], "t = 0.00 s")
    drawing.draw(frames[-1], f"t = {times[-1]:.2f} s")
    figure.canvas.draw()
    moved = np.asarray(figure.canvas.buffer_rgba()).copy()
    whole_figure, whole_ax = picture._figure(picture.SIZE)
    picture._draw(scene, whole_ax, frames[-1], f"t = {times[-1]:.2f} s")
    whole_figure.canvas.draw()
    whole = np.asarray(whole_figure.canvas.buffer_rgba())
    assert not np.array_equal(frames[0], frames[-1])  # the robot moved: the check says something
    assert np.array_equal(moved, whole)
