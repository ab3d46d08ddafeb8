"""Exercise 05: PPO's two computations, generalised advantage estimation and the clipped surrogate.

Check your work with ``python grade.py check --exercise ex05`` in the course folder (in the
project's repository: ``python course/grade.py check --exercise ex05``); see README.md. Write the
function yourself: a submission that calls an existing implementation of it (toolimit's, a
dependency's, the course's) scores 0 for the exercise.
"""

from __future__ import annotations

import numpy as np


def generalized_advantage_estimation(
    rewards: np.ndarray,
    values: np.ndarray,
    episode_starts: np.ndarray,
    last_values: np.ndarray,
    dones: np.ndarray,
    gamma: float,
    gae_lambda: float,
) -> tuple[np.ndarray, np.ndarray]:
    """Return ``(advantages, returns)`` of a rollout, both (T, E), exactly as stable-baselines3's
    ``RolloutBuffer.compute_returns_and_advantage`` computes them (write the recursion yourself:
    calling that method scores 0).

    The rollout has T steps of E environments. At step t, environment e observed a state of value
    ``values[t, e]``, acted and received ``rewards[t, e]``. ``episode_starts[t, e]`` is 1.0 when the
    state of step t began a new episode (so the step before it ended one), else 0.0. After the last
    step, ``last_values[e]`` is the value of the next state and ``dones[e]`` is 1.0 if the last step
    ended its episode.

    With delta_t = r_t + gamma V(s_{t+1}) (1 - done after step t) - V(s_t), the advantage is
    A_t = delta_t + gamma lambda (1 - done after step t) A_{t+1}, computed backwards from t = T-1;
    "done after step t" is ``dones`` for t = T-1 and ``episode_starts[t+1]`` otherwise. The returns
    are A_t + V(s_t).

    Args:
        rewards, values, episode_starts: (T, E) floats.
        last_values, dones: (E,) floats.
        gamma: discount in [0, 1]; gae_lambda: GAE's lambda in [0, 1].

    Returns:
        advantages (T, E) and returns (T, E), float arrays.
    """
    raise NotImplementedError("exercise 05: generalised advantage estimation")


def clipped_surrogate_loss(
    log_prob_new: np.ndarray, log_prob_old: np.ndarray, advantages: np.ndarray, clip_range: float
) -> float:
    """Return PPO's clipped policy loss (to be minimised), as stable-baselines3's PPO computes it.

    With ratio = exp(log_prob_new - log_prob_old), the loss is
    -mean(min(ratio A, clip(ratio, 1 - clip_range, 1 + clip_range) A)).

    Args:
        log_prob_new: (M,) log-probabilities of the rollout's actions under the policy being trained.
        log_prob_old: (M,) their log-probabilities under the policy that collected the rollout.
        advantages: (M,) advantages of those actions.
        clip_range: epsilon, e.g. 0.2 (the paper's authors used 0.05).

    Returns:
        The loss, a float.
    """
    raise NotImplementedError("exercise 05: the clipped surrogate loss")
