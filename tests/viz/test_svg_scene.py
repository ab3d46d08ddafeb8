"""A snapshot seen in a plane: segments as lines, points as markers, the ground, equal scales."""

from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np
import pytest

from toolimit.scenes.planar.spade import PlanarSpadeScene
from toolimit.viz.svg_scene import scene_plane_svg

SVG = "{http://www.w3.org/2000/svg}"


def legend(root):
    return [t.text for t in root.iter(f"{SVG}text") if t.get("class") == "legend"]


def test_segments_points_paths_and_ground_are_drawn():
    snapshot = {
        "walls": np.array([[[0.0, 0, 0], [0.0, 0, 0.1]], [[0.4, 0, 0], [0.4, 0, 0.1]]]),
        "sand": np.array([[0.1, 0, 0.02], [0.2, 0, 0.02], [0.3, 0, 0.02]]),
        "sand_radius": np.array(0.01),  # not an array of points: left out
    }
    head = np.array([[0.0, 0, 0.5], [0.2, 0, 0.3], [0.4, 0, 0.5]])
    root = ET.fromstring(scene_plane_svg(snapshot, "scene", paths={"head": head}, markers={"keypoints": head[[1]]}))
    assert legend(root) == ["ground (z = 0)", "walls", "sand", "head", "keypoints"]
    walls = [p for p in root.iter(f"{SVG}path") if p.find(f"{SVG}title").text == "walls"][0]
    assert walls.get("d").count("M") == 2  # one sub-path per wall
    sand = [g for g in root.iter(f"{SVG}g") if g.get("class") == "markers"][0]
    assert len(list(sand.iter(f"{SVG}circle"))) == 3


def test_a_planar_spade_snapshot_from_above_and_in_its_plane():
    scene = PlanarSpadeScene()
    params = {"sand_position": np.array([0.5, 0.0, 0.0]), "goal_position": np.array([1.2, 0.0, 0.0])}
    scene.reset(params, np.random.default_rng(0), batch_size=1)
    root = ET.fromstring(scene_plane_svg(scene.snapshot(), "planar spade"))
    assert {"walls", "sand"} <= set(legend(root))
    rect = next(r for r in root.iter(f"{SVG}rect") if r.get("fill") == "none")
    assert float(rect.get("width")) > float(rect.get("height"))  # the scene is wider than high at one scale
    assert "y (m)" in [
        t.text for t in ET.fromstring(scene_plane_svg(scene.snapshot(), "top", plane="xy")).iter(f"{SVG}text")
    ]


def test_footprints_are_outlined_from_above():
    root = ET.fromstring(
        scene_plane_svg({}, "top", footprints={"goal box": np.array([1.0, 2.0, 0.25, 0.25, 0.0])}, plane="xy")
    )
    (box,) = [p for p in root.iter(f"{SVG}path") if p.find(f"{SVG}title").text == "goal box"]
    assert box.get("d").count("L") == 4  # a closed rectangle: 5 corners
    assert "ground (z = 0)" not in legend(root)


def test_bad_input_is_refused():
    with pytest.raises(ValueError, match="unknown plane"):
        scene_plane_svg({}, "t", plane="yz")
    with pytest.raises(ValueError, match="nothing to draw"):
        scene_plane_svg({"radius": np.array(0.1)}, "t")
