"""Exercise 09 (an evening): one PPO update, graded by what it learns (stage iv).

PPO (``toolimit.learn``, notebook 05) alternates two phases: roll the current policy out, then
improve it on those rollouts with a few epochs of minibatch gradient steps on the clipped surrogate
and a value loss. Write the second phase. The grader runs the first (a 1-D "reach the goal" task:
16 episodes of 20 steps per update, rewards -|x - goal|, advantages by GAE) and calls your update
24 times; a policy that then reaches the goal in at least 80 % of 64 episodes (within 0.1, acting
with its mean) passes the main part. Smaller parts check one update: the surrogate improves, the
value network fits the returns, every parameter comes back.

Check your work with ``python grade.py check --exercise ex09`` in the course folder (in the
project's repository: ``python course/grade.py check --exercise ex09``); see README.md. Write it
yourself: a submission that calls stable-baselines3's PPO training or the library's learning code
scores 0 for the exercise.

Written questions (answer in a few sentences each, in a file ``ex09_answers.md`` handed in with
this one):
1. What does the clip range protect against when the same rollouts are used for several epochs?
   What happens to your update's learning on the grader's task with ``clip_range`` = 10 (try it)?
2. Why normalise the advantages per minibatch, and why is it harmless for the policy gradient's
   direction but not for its size?
3. The project's cloned policies are fine-tuned with PPO at a clip of 0.05 and one epoch (the
   authors' settings). Why would a large, many-epoch update be especially harmful right after
   behaviour cloning?
"""

from __future__ import annotations

import numpy as np
from stable_baselines3.common.policies import ActorCriticPolicy


def ppo_update(
    policy: ActorCriticPolicy,
    observations: np.ndarray,
    actions: np.ndarray,
    old_log_probs: np.ndarray,
    advantages: np.ndarray,
    returns: np.ndarray,
    clip_range: float = 0.2,
    learning_rate: float = 3e-3,
    epochs: int = 4,
    minibatch_size: int = 64,
    seed: int = 0,
) -> dict[str, np.ndarray]:
    """Improve ``policy`` on one batch of rollouts; return its new parameters.

    Inputs (M samples): ``observations`` (M, 2) float32, ``actions`` (M, 1) float32 (the sampled
    actions), ``old_log_probs`` (M,) their log-probabilities under the policy that collected them,
    ``advantages`` (M,) and ``returns`` (M,) (GAE and advantages + values).

    Make one Adam optimiser (``learning_rate``) over ``policy.parameters()``; for each of ``epochs``
    passes, shuffle the samples (``np.random.default_rng(seed)``) and take one Adam step per
    minibatch of ``minibatch_size`` samples on
        loss = -mean(min(rho A, clip(rho, 1 - clip_range, 1 + clip_range) A)) + 0.5 mean((V - returns)^2)
    where rho = exp(log pi(a | s) - old log prob) and V the value (``policy.evaluate_actions(obs,
    actions)`` gives values, log-probabilities and entropies as tensors), and A the minibatch's
    advantages normalised to mean 0 and standard deviation 1 (add 1e-8 to the standard deviation).

    Return ``{name: array}`` for every entry of ``policy.state_dict()`` after the update (numpy
    arrays: ``tensor.detach().numpy()``).
    """
    raise NotImplementedError("exercise 09: write PPO's update")
