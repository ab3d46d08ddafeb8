"""Scenes: simulated worlds a tool moves through (planar on pymunk, 3D batched particles)."""

from toolimit.errors import InvalidSceneParameters
from toolimit.scenes.base import CONTROL_FPS, ParameterSpec, Scene, SceneParams
from toolimit.scenes.registry import available_scenes, make_scene, register_scene
from toolimit.scenes.replay import replay

__all__ = [
    "CONTROL_FPS",
    "InvalidSceneParameters",
    "ParameterSpec",
    "Scene",
    "SceneParams",
    "available_scenes",
    "make_scene",
    "register_scene",
    "replay",
]
