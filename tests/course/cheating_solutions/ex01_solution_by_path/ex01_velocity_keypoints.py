"""Cheats: loads the shipped reference solution from its file at run time (no import statement
names it; only the runtime guard can see it)."""

import importlib.util
import os


def velocity_keypoints(demo, fraction=0.05):
    here = os.path.dirname(os.path.realpath(__file__))
    for _ in range(6):
        candidate = os.path.join(here, "course", "solut" + "ions", "ex01_velocity_keypoints.py")
        if os.path.isfile(candidate):
            break
        here = os.path.dirname(here)
    spec = importlib.util.spec_from_file_location("helper", candidate)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.velocity_keypoints(demo, fraction)
