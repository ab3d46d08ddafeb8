"""A calibrated pinhole camera: intrinsics, pose in the world, projection and viewing rays.

Frames: the world is the project's (metres, z up, the ground at z = 0); the camera's axes are
OpenCV's (x right, y down, z forward); pixels have their origin at the image's top-left corner,
u to the right and v down. The camera file (JSON) is the one other tools write: ``width``,
``height`` (pixels), ``K`` (3x3 intrinsics) and ``world_from_camera`` (4x4: the camera's axes and
centre in the world frame).
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from toolimit.artifacts import save_json
from toolimit.errors import TrackError

#: The issue's benchmark camera: 1280 x 720 pixels, focal length 1000 px.
DEFAULT_WIDTH, DEFAULT_HEIGHT, DEFAULT_FOCAL = 1280, 720, 1000.0
#: The side camera's distance from the motion's centre (horizontal, metres) and height above the ground.
SIDE_DISTANCE, SIDE_HEIGHT = 3.5, 1.2


@dataclass(frozen=True, eq=False)
class Camera:
    """A pinhole camera without lens distortion.

    Attributes:
        width, height: image size, pixels.
        K: (3, 3) intrinsics: focal lengths fx, fy and principal point cx, cy in pixels.
        world_from_camera: (4, 4) pose: columns 0-2 of the rotation are the camera's x (right),
            y (down) and z (forward) axes in the world frame, column 3 its centre (metres).
    """

    width: int
    height: int
    K: np.ndarray
    world_from_camera: np.ndarray

    def __post_init__(self) -> None:
        K = np.array(self.K, dtype=float)
        pose = np.array(self.world_from_camera, dtype=float)
        if K.shape != (3, 3) or not np.all(np.isfinite(K)):
            raise TrackError(f"camera K: expected a finite 3x3 matrix, got shape {K.shape}")
        if not (K[0, 0] > 0 and K[1, 1] > 0) or not np.allclose(K[2], [0.0, 0.0, 1.0]) or K[1, 0] != 0:
            raise TrackError(
                f"camera K: expected [[fx, s, cx], [0, fy, cy], [0, 0, 1]] with fx, fy > 0, got {K.tolist()}"
            )
        if pose.shape != (4, 4) or not np.all(np.isfinite(pose)):
            raise TrackError(f"camera world_from_camera: expected a finite 4x4 matrix, got shape {pose.shape}")
        rotation = pose[:3, :3]
        if not np.allclose(pose[3], [0.0, 0.0, 0.0, 1.0]) or not np.allclose(
            rotation.T @ rotation, np.eye(3), atol=1e-6
        ):
            raise TrackError("camera world_from_camera: its 3x3 block must be a rotation and its last row 0 0 0 1")
        if np.linalg.det(rotation) < 0:
            raise TrackError("camera world_from_camera: its 3x3 block is a reflection (det -1), not a rotation")
        for name in ("width", "height"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value <= 0:
                raise TrackError(f"camera {name}: expected a positive whole number of pixels, got {value!r}")
            object.__setattr__(self, name, int(value))
        K.setflags(write=False)
        pose.setflags(write=False)
        object.__setattr__(self, "K", K)
        object.__setattr__(self, "world_from_camera", pose)

    @property
    def centre(self) -> np.ndarray:
        """(3,) the camera's optical centre in the world, metres."""
        return self.world_from_camera[:3, 3]

    @property
    def rotation(self) -> np.ndarray:
        """(3, 3) the camera's axes (columns: x right, y down, z forward) in the world frame."""
        return self.world_from_camera[:3, :3]

    def project(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Pixels (N, 2) of world ``points`` (N, 3) and their depths (N,) along the optical axis,
        metres (a point behind the camera has depth <= 0 and meaningless pixels)."""
        in_camera = (np.asarray(points, dtype=float) - self.centre) @ self.rotation
        depth = in_camera[:, 2]
        with np.errstate(divide="ignore", invalid="ignore"):
            pixels = (in_camera @ self.K.T)[:, :2] / depth[:, None]
        return pixels, depth

    def rays(self, pixels: np.ndarray) -> np.ndarray:
        """(N, 3) unit directions in the world of the viewing rays through ``pixels`` (N, 2)."""
        pixels = np.asarray(pixels, dtype=float)
        homogeneous = np.column_stack([pixels, np.ones(len(pixels))])
        directions = np.linalg.solve(self.K, homogeneous.T).T @ self.rotation.T
        return directions / np.linalg.norm(directions, axis=1, keepdims=True)

    def inside(self, pixels: np.ndarray, depth: np.ndarray) -> np.ndarray:
        """(N,) whether each pixel lies in the image and in front of the camera."""
        u, v = pixels[:, 0], pixels[:, 1]
        with np.errstate(invalid="ignore"):
            return (depth > 0) & (u >= 0) & (u <= self.width - 1) & (v >= 0) & (v <= self.height - 1)

    def to_json(self) -> dict[str, object]:
        """The camera file's content (see the module docstring)."""
        return {
            "width": self.width,
            "height": self.height,
            "K": self.K.tolist(),
            "world_from_camera": self.world_from_camera.tolist(),
        }


def look_at(
    position: np.ndarray,
    target: np.ndarray,
    width: int = DEFAULT_WIDTH,
    height: int = DEFAULT_HEIGHT,
    focal: float = DEFAULT_FOCAL,
) -> Camera:
    """A level camera (no roll: its x axis is horizontal) at ``position`` (3,) looking at ``target``
    (3,), world metres, with focal length ``focal`` px and the principal point at the image centre."""
    position, target = np.asarray(position, dtype=float), np.asarray(target, dtype=float)
    forward = target - position
    if np.linalg.norm(forward[:2]) < 1e-9:
        raise TrackError("camera: looking straight up or down; a level camera needs a horizontal viewing direction")
    forward /= np.linalg.norm(forward)
    right = np.cross(forward, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    down = np.cross(forward, right)
    pose = np.eye(4)
    pose[:3, :3] = np.column_stack([right, down, forward])
    pose[:3, 3] = position
    K = np.array([[focal, 0.0, (width - 1) / 2], [0.0, focal, (height - 1) / 2], [0.0, 0.0, 1.0]])
    return Camera(width, height, K, pose)


def side_camera(
    points: np.ndarray,
    distance: float = SIDE_DISTANCE,
    height: float = SIDE_HEIGHT,
    width: int = DEFAULT_WIDTH,
    image_height: int = DEFAULT_HEIGHT,
    focal: float = DEFAULT_FOCAL,
    other_side: bool = False,
) -> Camera:
    """A camera beside a motion: ``height`` metres above the ground, ``distance`` metres from the
    centre of ``points`` (N, 3) (the tool's path, world metres) across the motion's main horizontal
    direction, looking at that centre. Of the two sides, the one towards -y of the main direction
    turned left (a fixed rule, so that the same points give the same camera), or with
    ``other_side`` the opposite one."""
    points = np.asarray(points, dtype=float)
    centre = points.mean(axis=0)
    horizontal = points[:, :2] - centre[:2]
    _, _, vt = np.linalg.svd(horizontal, full_matrices=False)
    main = vt[0] if vt[0][0] >= 0 else -vt[0]
    across = np.array([-main[1], main[0]])  # the main direction turned left
    position = np.array([*(centre[:2] + (1 if other_side else -1) * distance * across), height])
    return look_at(position, centre, width, image_height, focal)


def read_camera(path: str | os.PathLike[str]) -> Camera:
    """The camera file at ``path``; TrackError naming the file and the field that is wrong."""
    path = Path(path)
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except json.JSONDecodeError as error:
        raise TrackError(f"{path}: not a JSON file ({error})") from None
    if not isinstance(data, dict):
        raise TrackError(f"{path}: expected a JSON object with width, height, K, world_from_camera")
    missing = [key for key in ("width", "height", "K", "world_from_camera") if key not in data]
    if missing:
        raise TrackError(f"{path}: missing field(s) {', '.join(missing)}")
    try:
        K = np.array(data["K"], dtype=float)
        pose = np.array(data["world_from_camera"], dtype=float)
    except (TypeError, ValueError):
        raise TrackError(f"{path}: K and world_from_camera must be nested lists of numbers") from None
    try:
        return Camera(data["width"], data["height"], K, pose)
    except TrackError as error:
        raise TrackError(f"{path}: {error}") from None


def write_camera(camera: Camera, path: str | os.PathLike[str]) -> None:
    """Write ``camera`` to ``path`` as the camera file, atomically."""
    save_json(path, camera.to_json())
