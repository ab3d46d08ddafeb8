"""Stage (iv): learn the robot's policy (environments, behaviour cloning, PPO, evaluation).

``import toolimit.learn`` registers the Gymnasium ids ``toolimit/<Tool><World>-v0``
(:mod:`.env`). A :class:`LearningTask` (:mod:`.task`) holds what stages ii and iii hand over: the
scene parameters, the robot's base and reference joint trajectory, and the episode horizon.
:class:`BatchedTaskVecEnv` (:mod:`.vec_env`) steps B instances in one batched scene for SB3.
Domain randomisation of the goal box: :mod:`.adr`; where a policy succeeds as the box moves:
:mod:`.heat_map`. ``learn_policy(task, out_dir, LearningConfig(...))`` (:mod:`.training`) clones
and fine-tunes a policy, ``load_policy`` reads it back and ``evaluate`` (:mod:`.evaluate`)
measures it.
"""

from toolimit.learn.env import ToolUseEnv, env_id, register_environments
from toolimit.learn.evaluate import Evaluation, evaluate
from toolimit.learn.shipped import shipped_task, shipped_tasks
from toolimit.learn.simulator import TaskSimulator
from toolimit.learn.task import (
    LearningTask,
    TaskFileError,
    task_from_pipeline,
    task_from_trajectory,
)
from toolimit.learn.training import LearningConfig, LearningOutcome, learn_policy, load_policy
from toolimit.learn.vec_env import BatchedTaskVecEnv

register_environments()

__all__ = [
    "BatchedTaskVecEnv",
    "Evaluation",
    "LearningConfig",
    "LearningOutcome",
    "LearningTask",
    "TaskFileError",
    "TaskSimulator",
    "ToolUseEnv",
    "env_id",
    "evaluate",
    "learn_policy",
    "load_policy",
    "register_environments",
    "shipped_task",
    "shipped_tasks",
    "task_from_pipeline",
    "task_from_trajectory",
]
