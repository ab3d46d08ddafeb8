"""Tool shapes: dimensions follow ToolSpec and the tool frame; numpy and coal agree."""

from __future__ import annotations

import coal
import numpy as np
import pinocchio as pin
import pytest

from toolimit.scenes.spatial.shapes import (
    box_signed_distance,
    capsule_signed_distance,
    posed_tool_shapes,
)
from toolimit.scenes.spatial.tool_geometry import (
    SPADE_BLADE_LENGTH,
    SPADE_BLADE_WIDTH,
    SPADE_RIM_HEIGHT,
    tool_boxes,
    tool_shapes,
)
from toolimit.tools import TOOLS, tool_poses, tool_spec


def _bounds(shapes) -> tuple[np.ndarray, np.ndarray]:
    """Tool-frame bounding box (low, high) of all boxes (axis-aligned here) and capsules."""
    radii = shapes.capsule_radii[:, None]
    low = np.min(np.concatenate([shapes.box_centers - shapes.box_half_extents,
                                 np.minimum(shapes.capsule_starts, shapes.capsule_ends) - radii]), 0)
    high = np.max(np.concatenate([shapes.box_centers + shapes.box_half_extents,
                                  np.maximum(shapes.capsule_starts, shapes.capsule_ends) + radii]), 0)
    return low, high


@pytest.mark.parametrize("tool", sorted(TOOLS))
def test_numpy_shapes_and_pinocchio_model_describe_the_same_geometry(tool: str) -> None:
    shapes = tool_shapes(tool)
    model = shapes.geometry_model
    assert model.ngeoms == len(shapes.boxes) + len(shapes.capsules)
    for box, obj in zip(shapes.boxes, model.geometryObjects[: len(shapes.boxes)]):
        assert obj.name == f"{tool}/{box.name}"
        assert isinstance(obj.geometry, coal.Box)
        np.testing.assert_allclose(obj.geometry.halfSide, box.half_extents)
        np.testing.assert_allclose(obj.placement.translation, box.center)
        np.testing.assert_allclose(obj.placement.rotation, box.rotation)
        assert obj.meshColor.shape == (4,)
    for capsule, obj in zip(shapes.capsules, model.geometryObjects[len(shapes.boxes):]):
        assert isinstance(obj.geometry, coal.Capsule)
        assert obj.geometry.radius == pytest.approx(capsule.radius)
        assert obj.geometry.halfLength == pytest.approx(capsule.half_length)
        start, end = capsule.endpoints
        np.testing.assert_allclose(obj.placement.act(np.array([0, 0, -capsule.half_length])), start, atol=1e-12)
        np.testing.assert_allclose(obj.placement.act(np.array([0, 0, capsule.half_length])), end, atol=1e-12)
    np.testing.assert_allclose(shapes.capsule_starts[0], shapes.capsules[0].endpoints[0])


@pytest.mark.parametrize("tool", sorted(TOOLS))
def test_handle_reaches_beyond_the_handle_end_and_head_starts_at_the_head_point(tool: str) -> None:
    shapes, spec = tool_shapes(tool), tool_spec(tool)
    low, high = _bounds(shapes)
    assert spec.length < high[2] <= spec.length + 0.08, "the grip must pass the handle end by a few cm"
    assert low[2] == pytest.approx(-spec.head_length / 2 if tool == "hammer" else 0.0, abs=0.02)


def test_spade_blade_rim_and_handle_dimensions() -> None:
    boxes = {b.name: b for b in tool_boxes("spade")}
    blade = boxes["blade"]
    assert tool_boxes("spade")[0].name == "blade"
    # Carrying face is the plane x = 0 with the plate behind it (x < 0).
    assert blade.center[0] + blade.half_extents[0] == pytest.approx(0.0)
    # The original scene's blade: about 0.17 m across by 0.12 m along the tool (tool_geometry docstring).
    assert 2 * blade.half_extents[1] == pytest.approx(SPADE_BLADE_WIDTH) == pytest.approx(0.17)
    assert 2 * blade.half_extents[2] == pytest.approx(SPADE_BLADE_LENGTH) == pytest.approx(0.12)
    for name in ("rim_left", "rim_right", "rim_back"):
        rim = boxes[name]
        assert rim.center[0] + rim.half_extents[0] == pytest.approx(SPADE_RIM_HEIGHT), "rims stand on the +x face"
    assert boxes["rim_left"].center[1] > 0 > boxes["rim_right"].center[1]
    assert boxes["rim_back"].center[2] > SPADE_BLADE_LENGTH / 2, "the back rim is on the handle side; the tip is open"
    handle = tool_shapes("spade").capsules[0]
    start, end = handle.endpoints
    total = end[2] + handle.radius - (boxes["socket"].center[2] - boxes["socket"].half_extents[2])
    assert 0.4 <= total <= 0.5


def test_hammer_and_scythe_working_parts() -> None:
    head = tool_boxes("hammer")[0]
    spec = tool_spec("hammer")
    np.testing.assert_allclose(head.center, 0.0)
    assert 2 * head.half_extents[0] == pytest.approx(spec.head_width)  # striking axis is x
    assert 2 * head.half_extents[2] == pytest.approx(spec.head_length)
    blade = tool_boxes("scythe")[0]
    scythe = tool_spec("scythe")
    # the authors' blade: from the snath's side (2 cm) along +x, 4 cm along the snath, 1 cm thick
    assert blade.center[0] - blade.half_extents[0] == pytest.approx(0.02)
    assert 2 * blade.half_extents[0] == pytest.approx(scythe.head_width)
    assert 2 * blade.half_extents[2] == pytest.approx(scythe.head_length)
    assert 2 * blade.half_extents[1] == pytest.approx(0.01)


def test_unknown_tool_is_a_clear_error() -> None:
    with pytest.raises(ValueError, match="unknown tool 'rake'"):
        tool_shapes("rake")


def test_signed_distances_match_coal_for_posed_tool_shapes() -> None:
    """The vectorised distances of shapes.py agree with coal's GJK distances in the world frame."""
    rng = np.random.default_rng(3)
    shapes = tool_shapes("spade")
    pose = tool_poses(np.array([0.3, -0.2, 0.5]), np.array([0.5, 0.1, 0.8]), roll=0.7)
    world = posed_tool_shapes(shapes, pose.position, pose.rotation)
    points = pose.position + rng.normal(scale=0.25, size=(40, 3))
    sphere = coal.Sphere(1e-9)
    request, result = coal.DistanceRequest(), coal.DistanceResult()
    for k, box in enumerate(shapes.boxes):
        distance, normal = box_signed_distance(
            points, world["box_centers"][k], world["box_rotations"][k], world["box_half_extents"][k]
        )
        placement = pin.SE3(world["box_rotations"][k], world["box_centers"][k])
        for point, d, nrm in zip(points, distance, normal):
            result.clear()
            reference = coal.distance(
                coal.Box(*(2 * box.half_extents)), coal.Transform3s(placement.rotation, placement.translation),
                sphere, coal.Transform3s(np.eye(3), point), request, result,
            )
            assert d == pytest.approx(reference, abs=1e-6)
            assert np.linalg.norm(nrm) == pytest.approx(1.0)
    capsule = shapes.capsules[0]
    distance, _ = capsule_signed_distance(points, world["capsule_starts"][0], world["capsule_ends"][0], capsule.radius)
    middle = (world["capsule_starts"][0] + world["capsule_ends"][0]) / 2
    for point, d in zip(points, distance):
        result.clear()
        reference = coal.distance(
            coal.Capsule(capsule.radius, 2 * capsule.half_length), coal.Transform3s(pose.rotation, middle),
            sphere, coal.Transform3s(np.eye(3), point), request, result,
        )
        assert d == pytest.approx(reference, abs=1e-6)
