"""The authors' episode cut for the tools whose goal is timed (hammer, scythe), with the motion
carried on after the goal instead of stopped.

Their success is timed from the episode's start (the paper's "within the first second"), so the
episode must start shortly before the goal: the authors (learning-from-video
``II_trajectory_optimization/I_repeate_tool_traj.py`` and ``main.py``) replay the aligned tool
motion only up to the first control step that earns a goal reward (the first nail planted, the first
stalk cut), append ``AFTER_REWARD_FRAMES`` (5) steps, and keep the last ``KEPT_FRAMES`` (20) poses
(fewer when the motion is shorter) as the trajectory optimisation's target; the policy's horizon is
that trajectory's length (``train_ppo.py``), 20 steps = 0.83 s at 24 Hz, inside the success window.

One departure (docs/original_setup.md#the-timed-tools-and-the-talos-as-the-authors-built-them):
the authors' 5 appended steps hold the tool still at its first rewarded pose
(``add_zero_end_steps``); here they are the motion's own next 5 frames (the last pose held only
past the motion's end). Held still, the target stops a scythe's draw from 1.3-1.7 m/s within one
42 ms step, some 36 m/s^2, which no arm within its acceleration limits follows: the Panda's
trajectory then tracks its candidates' draws too slowly to cut (0.1-0.4 stalks in the learning
task on ``scythe_00``, 1.1-1.4 with the motion carried on). A person does not stop the blade at
the first stalk either.

The alignment finds the cut for each candidate (:mod:`toolimit.align.search`) and every later
stage reads the cut motion from the alignment's files, which record it (``first_reward_frame``,
``episode_start_frame``, ``episode_frames``). A scene's goal is timed when it is a
:class:`~toolimit.scenes.base.WindowedGoalScene`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from toolimit.scenes.base import Scene, WindowedGoalScene

#: Steps kept after the first rewarded step (as many as the authors' ``add_zero_end_steps``).
AFTER_REWARD_FRAMES = 5
#: Poses kept from the end of the cut motion (the authors' ``take_last_n_points``).
KEPT_FRAMES = 20


def is_timed(scene: Scene) -> bool:
    """True for a scene whose success is timed from the episode's start (hammer, scythe)."""
    return isinstance(scene, WindowedGoalScene)


@dataclass(frozen=True)
class EpisodeCut:
    """Where a timed tool's episode lies in its aligned motion (the module docstring).

    Attributes:
        first_reward_frame: index of the first pose whose control step earned a goal reward
            (frames of the aligned motion at the scene's control rate).
    """

    first_reward_frame: int

    @property
    def start(self) -> int:
        """The first kept frame of the aligned motion."""
        return max(0, self.first_reward_frame + 1 + AFTER_REWARD_FRAMES - KEPT_FRAMES)

    @property
    def frames(self) -> int:
        """Frames of the cut motion (at most ``KEPT_FRAMES``)."""
        return self.first_reward_frame + 1 + AFTER_REWARD_FRAMES - self.start

    def apply(self, frames: np.ndarray) -> np.ndarray:
        """The cut of per-frame values ``frames`` (T, ...): frames ``start`` to ``first_reward_frame``
        and the ``AFTER_REWARD_FRAMES`` after it, the last frame held where the motion ends sooner."""
        kept = frames[self.start : self.first_reward_frame + 1 + AFTER_REWARD_FRAMES]
        return np.concatenate([kept, np.repeat(kept[-1:], self.frames - len(kept), axis=0)])

    def record(self) -> dict[str, Any]:
        """JSON values for the alignment's record."""
        return {
            "first_reward_frame": self.first_reward_frame,
            "episode_start_frame": self.start,
            "episode_frames": self.frames,
            "frames_after_reward": AFTER_REWARD_FRAMES,
        }


def first_reward_cut(rewards: np.ndarray) -> EpisodeCut | None:
    """The cut from the goal rewards (T, B) of B replays after each of T control steps: the first
    rewarded replay (in order, as the authors take the first rewarded of their seeds) and its first
    rewarded step; None when no replay earned a reward."""
    rewarded = np.asarray(rewards) > 0.0
    replays = np.flatnonzero(rewarded.any(axis=0))
    if len(replays) == 0:
        return None
    return EpisodeCut(int(np.argmax(rewarded[:, replays[0]])))
