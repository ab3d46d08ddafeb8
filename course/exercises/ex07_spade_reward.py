"""Exercise 07 (an evening): the spade's rewards and success rule, in the planar world.

The planar spade scene (``toolimit.scenes.planar.spade``) scores an episode three ways: the goal
reward (how many sand circles are in the goal box), the paper appendix's dense shaping (how close
the sand is to the box, plus a little for the spade near the deposit), and the success rule (enough
sand in the box for at least half of the episode). PPO learns from the first, the project's dense
baseline from the second, and every figure of the paper's Table I counts the third. Write all
four functions; each is graded on its own (partial credit per part).

Check your work with ``python grade.py check --exercise ex07`` in the course folder (in the
project's repository: ``python course/grade.py check --exercise ex07``); see README.md. Write the
functions yourself: a submission that calls the library's spade scene, its shaping or its success
tracker scores 0 for the exercise.

Written questions (answer in a few sentences each, in a file ``ex07_answers.md`` handed in with
this one):
1. The goal reward is sparse: 0 until sand lands in the box. Why can PPO started from a random
   policy not learn from it on the spade, and what in the method makes it learnable?
2. The success rule asks for the goal to be met on half of the steps, not at the last step. Which
   behaviour would "at the last step" reward that the paper does not want, and which does the
   half-of-the-steps rule refuse?
3. The dense shaping adds 0.05 times the spade's closeness to the deposit. What could a policy
   learn if that weight were 1, and why does a sand term averaged over the circles not have this
   problem?
"""

from __future__ import annotations

import numpy as np


def goal_reward(sand: np.ndarray, box_x: np.ndarray, half_width: float, wall_height: float) -> np.ndarray:
    """Return the number of sand circles in the goal box, per instance: a (B,) float array.

    ``sand`` (B, N, 2): circle centres in the scene's x-z plane, metres (z up, the ground at 0).
    ``box_x`` (B,): the x of the goal box's centre (where the box is now, it can be pushed), m.
    A circle is in the box when its centre lies strictly between the walls, |x - box_x| <
    ``half_width``, and strictly below their top, z < ``wall_height``.
    """
    raise NotImplementedError("exercise 07: count the circles in the goal box")


def dense_reward(
    sand: np.ndarray, box_x: np.ndarray, handle_end: np.ndarray | None, deposit_x: float | np.ndarray
) -> np.ndarray:
    """Return the appendix's dense shaping per instance, a (B,) float array in [0, 1.05].

    The mean over the circles c of exp(-0.5 b |c - g|^2), plus 0.05 exp(-0.5 b |p - d|^2), with
    b = 10 (1/m^2), g = (box_x, 0) the goal box's floor centre, p = ``handle_end`` (B, 2) the
    spade's handle end and d = (deposit_x, 0) the deposit's floor centre; all in the x-z plane, m.
    ``handle_end`` is None before the spade is placed (the first step): then there is no tool term.
    ``deposit_x`` is a float or a (B,) array.
    """
    raise NotImplementedError("exercise 07: the dense shaping")


def episode_success(goal_rewards: np.ndarray, success_count: int = 10) -> np.ndarray:
    """Return the success of each episode, a (B,) bool array.

    ``goal_rewards`` (B, T): the goal reward after each of the T control steps of B episodes. An
    episode succeeds when the goal reward is at least ``success_count`` on at least half of its
    steps (exactly half is enough). With T = 0 no episode succeeds.
    """
    raise NotImplementedError("exercise 07: the success rule")


def first_decisive_step(goal_rewards: np.ndarray, success_count: int = 10) -> np.ndarray:
    """Return, per episode, the first step after which its success is certain, a (B,) int array.

    Same inputs as :func:`episode_success`. Step t (0-based) is decisive when the steps 0..t alone
    already meet the success rule for the whole episode of T steps, whatever the later steps bring
    (an evaluation could stop the episode there). -1 where the episode never becomes certain (it
    fails).
    """
    raise NotImplementedError("exercise 07: when success becomes certain")
