"""When a scythe cuts a stalk: the authors' rule (pyphysx_envs ``ScytheTaskScene.cut_grasses``),
shared by the 3D scythe scene and its planar twin.

World frame: metres, z up, ground at z = 0; stalks are vertical segments standing on the ground.
The **cutting edge** is the segment ``edge`` (2, 3) in the tool frame (the blade's side towards the
handle, :mod:`toolimit.scenes.spatial.tool_geometry`); its **normal** is the tool's +z axis, along
the snath towards the handle. At every sampled pose (the scene's sub-steps, 240 Hz at 24 Hz
control with 10 sub-steps, as the authors check), a stalk not yet cut is cut when all hold:

* near: the closest points of the edge line and of the stalk's bottom ``stalk_reach`` (0.1 m),
  each clipped to its segment as the authors do, are at most ``4 * stalk_width`` (2 cm) apart,
  and one of the edge's end points is within ``stalk_width + blade_length / 2`` of the stalk in
  x-y (the authors' early-out);
* low: the edge's closest point is at most ``max_cut_height`` (0.1 m) above the ground;
* facing: the angle between the normal (3D, unit) and the horizontal direction from the edge's
  closest point to the stalk's foot is at most ``max_angle`` (30 degrees). The normal must be
  within 30 degrees of horizontal, so the snath too: a scythe held with its snath steeper than
  30 degrees cuts nothing;
* approaching: the velocity of the edge's closest point dotted with the horizontal vector from it
  to the stalk's foot (not normalised) exceeds ``threshold`` (0.02 m^2/s). At the 2 cm limit that
  is an approach at 1 m/s, at 1 cm 2 m/s.

Two details differ from the authors' code: the velocity is the edge point's own (the finite
difference of its position over the sub-step that ends at the tested pose), where the authors add
the tool's angular velocity crossed with the offset from the blade's root to the tool's linear
velocity at the grip, and from the previous sub-step; and the test runs at the end of each
sub-step, where theirs runs before the tool moves.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from toolimit.tools import tool_spec
from toolimit.tools.scythe import SCYTHE_SNATH_RADIUS

#: The authors' defaults (``ScytheTaskScene``, ``method/utils.py``): distance in stalk widths,
#: reach up the stalk (m), highest cut (m), largest normal angle (rad), approach threshold (m^2/s).
CUT_DISTANCE_WIDTHS = 4.0
STALK_REACH = 0.1
MAX_CUT_HEIGHT = 0.1
MAX_NORMAL_ANGLE = np.pi / 6
CUTTING_THRESHOLD = 0.02
#: The authors' grass patch (``grass_patch_len``, ``grass_patch_width``): length along world x and
#: width along y, m; both scythe scenes' default and the scripted draw's (:mod:`toolimit.scenes.spatial.sweep`).
PATCH_SIZE = (0.4, 0.1)


@dataclass(frozen=True)
class ScytheCutRule:
    """The cut test of the module docstring.

    Attributes:
        edge: (2, 3) cutting edge root and tip in the tool frame, m.
        normal: (3,) unit edge normal in the tool frame.
        stalk_width: side of a stalk, m.
        stalk_reach: how far up a stalk the closest point may lie, m.
        max_cut_height: highest edge point that cuts, m.
        max_angle: largest angle between the normal and the direction to the stalk, rad.
        threshold: smallest approach (velocity dotted with the offset to the stalk), m^2/s.
    """

    edge: np.ndarray
    normal: np.ndarray
    stalk_width: float
    stalk_reach: float = STALK_REACH
    max_cut_height: float = MAX_CUT_HEIGHT
    max_angle: float = MAX_NORMAL_ANGLE
    threshold: float = CUTTING_THRESHOLD

    @property
    def blade_length(self) -> float:
        """Length of the edge, m."""
        return float(np.linalg.norm(self.edge[1] - self.edge[0]))

    def cuts(self, positions: np.ndarray, rotations: np.ndarray, stalks_xy: np.ndarray, dt: float) -> np.ndarray:
        """(S, B, N) bool: stalk n of instance b meets the rule at the end of sub-step s.

        Args:
            positions: (S+1, B, 3) tool positions at the sub-step instants, world, m.
            rotations: (S+1, B, 3, 3) world-from-tool rotations at the same instants.
            stalks_xy: (B, N, 2) stalk feet, world x-y, m.
            dt: seconds per sub-step.
        """
        edges = positions[:, :, None, :] + np.einsum("sbij,ej->sbei", rotations, self.edge)  # (S+1, B, 2, 3)
        root, tip = edges[1:, :, 0], edges[1:, :, 1]  # (S, B, 3) at the tested instants
        length = np.linalg.norm(tip - root, axis=-1)  # (S, B)
        direction = (tip - root) / length[..., None]
        feet = np.concatenate([stalks_xy, np.zeros(stalks_xy.shape[:2] + (1,))], axis=-1)[None]  # (1, B, N, 3)
        offset = root[:, :, None, :] - feet  # (S, B, N, 3) stalk foot to edge root
        bz = direction[..., 2][..., None]  # (S, B, 1)
        be = np.einsum("sbk,sbnk->sbn", direction, offset)
        de = offset[..., 2]
        with np.errstate(divide="ignore", invalid="ignore"):  # a vertical edge (bz = 1) meets no stalk
            denominator = 1.0 - bz**2
            up = np.clip((de - be * bz) / denominator, 0.0, self.stalk_reach)  # along the stalk, m
            along = np.clip((de * bz - be) / denominator, 0.0, length[..., None])  # along the edge, m
        gap = offset + direction[:, :, None, :] * along[..., None]
        gap[..., 2] -= up
        distance = np.linalg.norm(gap, axis=-1)
        contact = root[:, :, None, :] + direction[:, :, None, :] * along[..., None]  # (S, B, N, 3)
        to_stalk = feet[..., :2] - contact[..., :2]  # horizontal, m
        normal = np.einsum("sbij,j->sbi", rotations[1:], self.normal)  # (S, B, 3) world
        with np.errstate(divide="ignore", invalid="ignore"):
            cosine = np.einsum("sbk,sbnk->sbn", normal[..., :2], to_stalk) / np.linalg.norm(to_stalk, axis=-1)
        # The contact point's velocity over the sub-step ending now: its tool-frame point moved rigidly.
        local = np.einsum(
            "sbji,sbnj->sbni", rotations[1:], contact - positions[1:, :, None, :]
        )  # (S, B, N, 3) tool frame
        before = positions[:-1, :, None, :] + np.einsum("sbij,sbnj->sbni", rotations[:-1], local)
        velocity = (contact - before) / dt
        approach = np.einsum("sbnk,sbnk->sbn", velocity[..., :2], to_stalk)
        reach = self.stalk_width + self.blade_length / 2
        near_end = (np.linalg.norm(root[:, :, None, :2] - feet[..., :2], axis=-1) <= reach) | (
            np.linalg.norm(tip[:, :, None, :2] - feet[..., :2], axis=-1) <= reach
        )
        return (
            near_end
            & np.isfinite(distance)
            & (distance <= CUT_DISTANCE_WIDTHS * self.stalk_width)
            & (contact[..., 2] <= self.max_cut_height)
            & (np.nan_to_num(cosine, nan=-1.0) >= np.cos(self.max_angle))
            & (approach > self.threshold)
        )


def scythe_cut_rule(stalk_width: float, max_cut_height: float = MAX_CUT_HEIGHT) -> ScytheCutRule:
    """The authors' rule for the registered scythe: its edge is the blade's side towards the handle
    (tool frame: x from the snath's side over ``head_width``, z = ``head_length / 2``), its normal
    the tool's +z; stalks ``stalk_width`` m wide, cut at most ``max_cut_height`` m high."""
    spec = tool_spec("scythe")
    z = spec.head_length / 2
    edge = np.array([[SCYTHE_SNATH_RADIUS, 0.0, z], [SCYTHE_SNATH_RADIUS + spec.head_width, 0.0, z]])
    return ScytheCutRule(edge, np.array([0.0, 0.0, 1.0]), stalk_width, max_cut_height=max_cut_height)
