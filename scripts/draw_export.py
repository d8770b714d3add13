"""Draw docs/img/export.png: the example 4x4x4 crawler's exported surface (what the .glb holds,
read back with trimesh), coloured by material. `python scripts/draw_export.py`."""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np
import trimesh
from mpl_toolkits.mplot3d.art3d import Poly3DCollection

from softevo.core.outputs import figures
from softevo.core.outputs.export import Z_UP_TO_Y_UP, export_robot
from softevo.core.robots.robot import COLOURS
from softevo.core.robots.robot_file import load_robot

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    robot = load_robot(ROOT / "examples" / "crawler_4x4x4.json")
    scene = trimesh.load(io.BytesIO(export_robot(robot, "glb")), file_type="glb")
    plt = figures.pyplot()
    figure = plt.figure(figsize=(5.0, 4.2))
    ax = figure.add_subplot(projection="3d")
    faces, colours = [], []
    for label, mesh in scene.geometry.items():
        faces.append((mesh.vertices @ Z_UP_TO_Y_UP)[mesh.faces])  # glTF +Y up back to +Z up
        colour = np.array(COLOURS[label]) / 255
        colours += [colour] * len(mesh.faces)
        ax.plot([], [], "s", color=colour, label=label)
    # one collection, so that matplotlib sorts every face by depth together
    ax.add_collection3d(Poly3DCollection(np.concatenate(faces), facecolor=colours, linewidth=0))
    ax.set(xlim=(0, 4), ylim=(0, 4), zlim=(0, 4), xlabel="x (m)", ylabel="y (m)", zlabel="z (m)")
    ax.set_box_aspect((1, 1, 1))
    ax.view_init(elev=24, azim=-58)
    ax.legend(loc="upper left", fontsize=8, frameon=False)
    ax.set_title("examples/crawler_4x4x4.json as crawler.glb", fontsize=9)
    figure.tight_layout()
    figures.save(figure, ROOT / "docs" / "img" / "export.png")


if __name__ == "__main__":
    main()
