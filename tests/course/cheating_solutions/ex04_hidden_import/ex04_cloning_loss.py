"""Cheats: the library's cloning loss behind a computed module name and getattr, and an
``except BaseException`` that swallows the guard's interruption."""

import importlib


def cloning_loss(policy, observations, expert_actions):
    module = importlib.import_module(".".join(["toolimit", "learn", "clo" + "ning"]))
    loss = None
    try:  # noqa: SIM105 - on purpose: it swallows the guard's interruption
        loss = getattr(module, "mean_" + "action_loss")(policy, observations, expert_actions)
    except BaseException:
        pass
    return loss
