"""Cheats: hands the batch to stable-baselines3's own PPO training loop."""

from stable_baselines3 import PPO


def ppo_update(
    policy,
    observations,
    actions,
    old_log_probs,
    advantages,
    returns,
    clip_range=0.2,
    learning_rate=3e-3,
    epochs=4,
    minibatch_size=64,
    seed=0,
):
    PPO.train(None)
    return {name: value.detach().numpy() for name, value in policy.state_dict().items()}
