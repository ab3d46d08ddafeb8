"""Motion-estimator pickles: canonicalisation recovers a known motion; malformed files are refused."""

from __future__ import annotations

import os
import pickle

import numpy as np
import pytest

from toolimit.demos import DemoError, load_demo, read_motion_estimate
from toolimit.demos.motion_estimator import CAMERA_TO_WORLD, LEFT_TOES, RIGHT_TOES, canonical_demo
from toolimit.tools import tool_spec

N = 40

# The estimator stores numpy matrices; building them here warns that np.matrix is old-fashioned.
pytestmark = pytest.mark.filterwarnings("ignore::PendingDeprecationWarning")


def _world_motion(length: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A person standing with the toes' mid-point at the world origin, swinging a tool in front."""
    t = np.linspace(0.0, 1.0, N)
    head = np.stack([0.3 * np.cos(2 * t), 0.5 + 0.2 * np.sin(2 * t), 0.05 + 0.4 * t], axis=1)
    axis = np.stack([-np.ones(N), np.zeros(N), 0.5 + t], axis=1)
    handle = head + length * axis / np.linalg.norm(axis, axis=1, keepdims=True)
    joints = np.zeros((N, 24, 3))
    joints[:, :, 2] = 1.0  # every other joint one metre up
    joints[:, LEFT_TOES] = [-0.12, 0.03, 0.0]
    joints[:, RIGHT_TOES] = [0.12, -0.03, 0.0]
    joints[:, 10] = [5.0, 5.0, 5.0]  # SMPL's foot indices hold something else in this rig
    joints[:, 11] = [5.0, 5.0, 5.0]
    return head, handle, joints


def _to_camera(points: np.ndarray, offset: np.ndarray) -> np.ndarray:
    return points @ CAMERA_TO_WORLD + offset  # inverse of (p - c) @ CAMERA_TO_WORLD.T


def _pickle(path, head, handle, joints, protocol: int = 2, **override) -> None:
    offset = np.array([0.3, 1.1, 3.5])  # the person stands 3.5 m in front of the camera
    data = {
        "fps": 24,
        "keypoint_3d_positions_object": np.matrix(
            np.vstack([_to_camera(handle, offset).T, _to_camera(head, offset).T])
        ),
        "joint_3d_positions_person": np.matrix(_to_camera(joints, offset).reshape(N, 72).T),
        "config_object": np.matrix(np.zeros((N, 7))),
    }
    data.update(override)
    data = {k: v for k, v in data.items() if v is not None}
    path.write_bytes(pickle.dumps(data, protocol=protocol))


@pytest.mark.parametrize("protocol", [2, 5])
def test_canonicalisation_recovers_the_world_motion(tmp_path, protocol):
    length = tool_spec("spade").length
    head, handle, joints = _world_motion(length)
    _pickle(tmp_path / "video.pkl", head, handle, joints, protocol)
    demo = load_demo(tmp_path / "video.pkl", tool="spade")
    np.testing.assert_allclose(demo.head, head, atol=1e-12)
    np.testing.assert_allclose(demo.handle, handle, atol=1e-12)
    assert demo.fps == 24 and demo.tool == "spade"


def test_camera_axes_become_world_axes(tmp_path):
    head, handle, joints = _world_motion(0.4)
    estimate_path = tmp_path / "spade_1_s7.pkl"
    _pickle(estimate_path, head, handle, joints)
    estimate = read_motion_estimate(estimate_path)
    # Camera y points down: the head, above the toes in the world, has a smaller camera y.
    assert np.all(estimate.head[:, 1] < estimate.toes_centre[1])
    # Camera z (depth) becomes world y (forward).
    np.testing.assert_allclose(estimate.head[:, 2] - estimate.toes_centre[2], head[:, 1], atol=1e-12)
    # The tool is named by the file name when not given.
    assert load_demo(estimate_path).tool == "spade"


def test_handle_is_put_at_the_tool_length(tmp_path):
    head, handle, joints = _world_motion(0.55)  # the estimate's stick is longer than our hammer
    _pickle(tmp_path / "hammer.pkl", head, handle, joints)
    demo = load_demo(tmp_path / "hammer.pkl")
    np.testing.assert_allclose(demo.lengths, tool_spec("hammer").length, atol=1e-12)
    np.testing.assert_allclose(demo.head, head, atol=1e-12)  # the paper's way keeps the head path
    np.testing.assert_allclose(demo.axis, (handle - head) / 0.55, atol=1e-12)


def test_rescale_motion_scales_about_the_toes(tmp_path):
    length = tool_spec("spade").length
    head, handle, joints = _world_motion(length)
    _pickle(tmp_path / "big.pkl", 1.3 * head, 1.3 * handle, 1.3 * joints)
    demo = canonical_demo(read_motion_estimate(tmp_path / "big.pkl"), "spade", rescale="motion")
    np.testing.assert_allclose(demo.head, head, atol=1e-12)
    np.testing.assert_allclose(demo.handle, handle, atol=1e-12)
    with pytest.raises(DemoError, match="rescale: expected 'tool' or 'motion'"):
        canonical_demo(read_motion_estimate(tmp_path / "big.pkl"), "spade", rescale="both")


class _RunsCode:
    def __reduce__(self):
        return (os.system, ("echo this must never run",))


def test_pickle_with_code_is_refused(tmp_path):
    path = tmp_path / "evil.pkl"
    path.write_bytes(pickle.dumps({"fps": _RunsCode()}))
    with pytest.raises(DemoError, match=r"evil\.pkl: not a readable motion estimator pickle \(refusing to load"):
        read_motion_estimate(path)


@pytest.mark.parametrize(
    "override, message",
    [
        ({"fps": None}, "missing key 'fps'"),
        ({"keypoint_3d_positions_object": None}, "missing key 'keypoint_3d_positions_object'"),
        ({"fps": -3}, "key 'fps' must be between 1 and 1000 frames per second"),
        (
            {"keypoint_3d_positions_object": np.zeros((5, N))},
            r"'keypoint_3d_positions_object' must have shape \(6, nf\), got \(5, 40\)",
        ),
        ({"joint_3d_positions_person": np.zeros((72, N + 1))}, "has 40 frames but 'joint_3d_positions_person' has 41"),
        (
            {"keypoint_3d_positions_object": np.full((6, N), np.nan)},
            "'keypoint_3d_positions_object' has NaN or inf at frames",
        ),
        ({"keypoint_3d_positions_object": np.zeros((6, N))}, "head and handle end coincide at frame 0"),
        (
            {
                "keypoint_3d_positions_object": np.tile([[0.0], [0], [0], [0], [0], [1]], 5),
                "joint_3d_positions_person": np.zeros((72, 5)),
            },
            "too few frames: 5",
        ),
    ],
)
def test_malformed_pickles(tmp_path, override, message):
    head, handle, joints = _world_motion(0.4)
    path = tmp_path / "spade_bad.pkl"
    _pickle(path, head, handle, joints, **override)
    with pytest.raises(DemoError, match=message) as error:
        load_demo(path)
    assert "spade_bad.pkl" in str(error.value)


def test_not_a_dict_and_truncated(tmp_path):
    (tmp_path / "list.pkl").write_bytes(pickle.dumps([1, 2, 3]))
    with pytest.raises(DemoError, match="expected a dict of arrays, got list"):
        read_motion_estimate(tmp_path / "list.pkl")
    head, handle, joints = _world_motion(0.4)
    _pickle(tmp_path / "cut.pkl", head, handle, joints)
    (tmp_path / "cut.pkl").write_bytes((tmp_path / "cut.pkl").read_bytes()[:100])
    with pytest.raises(DemoError, match=r"cut\.pkl: not a readable motion estimator pickle"):
        read_motion_estimate(tmp_path / "cut.pkl")
    with pytest.raises(FileNotFoundError):
        read_motion_estimate(tmp_path / "absent.pkl")
