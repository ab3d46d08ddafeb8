"""Settings of the alignment search, with the paper's values and the few places we depart from them.

Departures from the paper (Zorina et al. 2022, Sec. IV-A), each measured or taken from the
authors' code (kzorina/learning-from-video, ``method/I_alignment``):

* z offset p_z ~ N(0, 0.1 m) instead of N(0, 0.5 m): the paper's videos were placed by the
  demonstrator's feet, ours are metric and ground-referenced. In the first 300 samples of each
  of the five shipped spade demos (seed 0; ``benchmarks/alignment_planar.py --z-ablation``),
  0.1 m found 50 candidates and 0.5 m found 9: wide offsets bury the blade (rejected) or lift it
  clear of the sand.
* samples whose tool head goes more than 2 cm below the ground are rejected (``ground_tolerance``).
* as in the authors' code, the tool alone moves within 1 m/s and 2 rad/s per world axis
  (:func:`toolimit.scenes.replay.speed_limited`), and its reached poses are the robot's targets.
* screening (``screen_replays``): one run first, the 10 runs only for a sample that earned a
  reward in it, as the authors' code does (the paper only says "10 times"); a sample is a
  candidate when at least 2 of the 10 runs earn a reward (``accept_replays``; the authors'
  ``acceptable_success_n``, ``method/I_alignment/main.py``).
* the trajectory scale shrinks the motion about the ground point under the head path's centroid
  (the authors' code scaled about the demonstrator's feet), so the ground stays the ground.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from toolimit.errors import InvalidSetting
from toolimit.tools.registry import find_tool


def demo_plane(tool: str, world: str) -> str | None:
    """The plane the planar scene of ``tool`` lives in ("xz": vertical plane, "xy": horizontal
    plane; its record's ``planar_plane``), onto which the demonstration is projected before
    alignment; None in 3D and for a tool the registry does not know (its demonstration is kept as
    it is)."""
    record = find_tool(tool)
    return record.planar_plane if world == "planar" and record is not None else None


#: Planes whose scenes see the tool's working direction x only inside the plane. In the vertical
#: x-z plane the tool axis lies in the plane, so roll 0 and roll pi (the convention of
#: :mod:`toolimit.tools.frame`) are the two ways the blade can face within it; any other roll
#: points x out of the plane, where a planar scene cannot show it and a planar arm cannot hold it.
#: Turning the blade over from one face to the other would leave the plane, so a planar sample
#: keeps one face for the whole motion.
IN_PLANE_ROLLS: dict[str, tuple[float, float]] = {"xz": (0.0, float(np.pi))}

#: Index of the world axis normal to each plane (the coordinate a planar scene ignores).
PLANE_NORMAL_AXIS: dict[str, int] = {"xz": 1, "xy": 2}


@dataclass(frozen=True)
class AlignmentConfig:
    """How many samples to try and how to draw them.

    Attributes:
        samples: at most this many samples are tried (paper: 20,000).
        candidates: the search stops at the first K accepted samples (``accept_replays``).
        replays: each sample's trajectory is executed this many times (scene randomness), the goal
            reward is averaged (paper: 10).
        accept_replays: a sample is accepted as a candidate when at least this many of its
            ``replays`` runs earn a goal reward (the authors' code: 2 of 10; one lucky run of ten
            is not enough).
        screen_replays: if > 0, a sample is first replayed this many times and only one that
            earns a reward there gets the ``replays`` runs whose mean decides (the original code
            screens with one run, then checks with 10); 0 replays every sample ``replays`` times.
            Screening makes zero-reward samples ~10x cheaper; it can miss a sample that earns a
            reward in only a few of its 10 runs.
        scales: trajectory scales drawn uniformly (paper: 0.5, 0.75, 1).
        z_offset_std: standard deviation of the vertical offset p_z, metres. The paper draws
            p_z ~ N(0, 0.5) for videos whose height reference is a person's feet; our
            demonstrations are metric and ground-referenced already, so a tighter 0.1 m keeps the
            tool near the ground it works on and most samples useful.
        element_std: standard deviation, metres, of each Gaussian of the element mixture around a
            keypoint, isotropic (Sigma = element_std**2 I; the original code: 0.1 m). In a planar
            world the variance along the plane's normal is set to zero.
        ground_tolerance: a sample whose aligned tool head goes deeper than this below the
            ground (z = 0), metres, is rejected. Not in the paper: a kinematic tool passes through
            the ground in simulation, and such a motion is useless to a robot. Only the head (the
            working end) is checked: the handle end of the real spade recordings dips below it.
        keypoint_fraction: the top/bottom share of speeds whose local extrema are keypoints (0.05).
        max_attempts: draws of the element set before a sample counts as rejected by the sampler.
        chunk_size: samples per unit of work handed to a worker process (small, so that a search
            that has enough candidates waits little for chunks still running).
    """

    samples: int = 20_000
    candidates: int = 5
    replays: int = 10
    accept_replays: int = 2
    screen_replays: int = 1
    scales: tuple[float, ...] = (0.5, 0.75, 1.0)
    z_offset_std: float = 0.1
    element_std: float = 0.1
    ground_tolerance: float = 0.02
    keypoint_fraction: float = 0.05
    max_attempts: int = 100
    chunk_size: int = 10

    def __post_init__(self) -> None:
        for name in ("samples", "candidates", "replays", "max_attempts", "chunk_size"):
            value = getattr(self, name)
            if not (isinstance(value, (int, np.integer)) and value > 0):
                raise InvalidSetting(name, f"expected a positive integer, got {value!r}")
        if not (isinstance(self.accept_replays, (int, np.integer)) and 1 <= self.accept_replays <= self.replays):
            raise InvalidSetting(
                "accept_replays", f"expected an integer from 1 to replays ({self.replays}), got {self.accept_replays!r}"
            )
        if not (isinstance(self.screen_replays, (int, np.integer)) and self.screen_replays >= 0):
            raise InvalidSetting("screen_replays", f"expected a non-negative integer, got {self.screen_replays!r}")
        for name in ("z_offset_std", "element_std", "ground_tolerance"):
            value = getattr(self, name)
            if not (np.isfinite(value) and value >= 0):
                raise InvalidSetting(name, f"expected a non-negative number, got {value!r}")
        if not self.scales or not all(np.isfinite(s) and s > 0 for s in self.scales):
            raise InvalidSetting("scales", f"expected positive numbers, got {self.scales!r}")
        if not 0.0 < self.keypoint_fraction <= 1.0:
            raise InvalidSetting("keypoint_fraction", f"expected a value in (0, 1], got {self.keypoint_fraction}")

    def element_covariance(self, plane: str | None) -> np.ndarray:
        """(3, 3) covariance Sigma of the element mixture, m^2, world frame."""
        variance = np.full(3, self.element_std**2)
        if plane is not None:
            variance[PLANE_NORMAL_AXIS[plane]] = 0.0
        return np.diag(variance)

    def to_dict(self) -> dict[str, Any]:
        data = asdict(self)
        data["scales"] = list(self.scales)
        return data
