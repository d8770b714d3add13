"""A GIF or MP4 frame names the materials its colours stand for (issue 39: no legend)."""

from __future__ import annotations

from pathlib import Path

from softevo.core import picture
from softevo.core.robot_file import load_robot


def test_a_movie_frame_has_a_legend_of_the_robots_materials(examples: Path) -> None:
    scene = picture._Scene(load_robot(examples / "crawler_4x4x4.json"))
    names = [name for name, _ in scene.legend]
    assert names == ["soft", "hard", "actuated (sine)", "actuated (-sine)"]
    _figure, ax = picture._figure(picture.SIZE)
    picture._draw(scene, ax, scene.mechanics.positions, "t = 0.00 s")
    assert [text.get_text() for text in ax.get_legend().get_texts()] == names
    picture._draw(scene, ax, scene.mechanics.positions, None)  # a thumbnail: none
    assert ax.get_legend() is None
