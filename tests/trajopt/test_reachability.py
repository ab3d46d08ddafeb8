"""Static reachability: FK-generated targets are reachable, far ones are not."""

from __future__ import annotations

import numpy as np

from toolimit.trajopt import reachable_steps


def test_reachable_and_unreachable_targets(panda):
    rng = np.random.default_rng(0)
    base = np.array([0.2, -0.1, 0.5])
    q_random = rng.uniform(panda.lower, panda.upper, size=(4, panda.n_joints))
    reachable = [panda.tool_pose(q, base)[0] for q in q_random]
    far = [base + [3.0, 0.0, 0.5], base + [0.0, 0.0, 2.5]]
    result = reachable_steps(panda, base, np.array(reachable + far))
    np.testing.assert_array_equal(result, [True] * 4 + [False] * 2)
