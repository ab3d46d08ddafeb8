"""The paper's claims read off a reproduction's intervals: each reading and where it is written."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import numpy as np

from toolimit.experiments.cells import CellResult, Experiment
from toolimit.experiments.claims import read_claims
from toolimit.experiments.report import write_results
from toolimit.experiments.summary import summarise_cells, summarise_methods

PRESET = {"name": "quick", "quick": True, "settings_changes": {}}


def cell(demo: str, method: str, successes: list[bool], tool: str = "scythe") -> CellResult:
    """A 3D Panda cell with these episodes' successes (goal reward 10 for a success, 8 else)."""
    experiment = Experiment(tool, "3d", "panda", Path(f"{demo}.npz"))
    won = np.asarray(successes, dtype=bool)
    return CellResult.of(experiment, method, np.where(won, 10.0, 8.0), won)


def episodes(wins: int, of: int = 20) -> list[bool]:
    return [True] * wins + [False] * (of - wins)


def claim(runs: dict[int, list[CellResult]], name: str, tool: str = "scythe"):
    readings = read_claims(summarise_cells(runs), summarise_methods(runs))
    (found,) = [r for r in readings if r.claim == name and r.tool == tool]
    return found


def test_four_of_five_demonstrations_succeeding_on_their_whole_interval_hold_the_claim() -> None:
    finals = [cell(f"scythe_0{i}", "final", episodes(20)) for i in range(4)]
    finals.append(cell("scythe_04", "final", episodes(3)))
    reading = claim({0: finals}, "succeeds")
    assert reading.required == 4 and (reading.firmly, reading.on_the_means, reading.possibly) == (4, 4, 4)
    assert reading.reading == "holds" and reading.failing == ["scythe_04"]


def test_a_mean_at_the_threshold_whose_interval_reaches_below_holds_on_the_means_only() -> None:
    finals = [cell(f"scythe_0{i}", "final", episodes(20)) for i in range(3)]
    finals += [cell("scythe_03", "final", episodes(16)), cell("scythe_04", "final", episodes(0))]
    reading = claim({0: finals}, "succeeds")
    assert (reading.firmly, reading.on_the_means) == (3, 4)
    assert reading.reading == "holds on the means"


def test_too_few_on_their_means_could_still_hold_within_the_intervals_or_not_hold() -> None:
    near = [cell(f"scythe_0{i}", "final", episodes(20)) for i in range(3)]
    near += [cell("scythe_03", "final", episodes(14)), cell("scythe_04", "final", episodes(0))]
    assert claim({0: near}, "succeeds").reading == "could hold"  # 0.70 over 20 episodes reaches 0.8
    far = near[:3] + [cell("scythe_03", "final", episodes(4)), cell("scythe_04", "final", episodes(0))]
    reading = claim({0: far}, "succeeds")
    assert reading.reading == "does not hold" and reading.failing == ["scythe_03", "scythe_04"]


def test_seeds_that_disagree_widen_the_reading() -> None:
    """One demonstration that one of two seeds learns and the other does not: its interval spans
    0 to 1, so five demonstrations with it cannot hold the claim firmly."""
    runs = {seed: [cell(f"scythe_0{i}", "final", episodes(20)) for i in range(4)] for seed in (0, 1)}
    runs[0].append(cell("scythe_04", "final", episodes(20)))
    runs[1].append(cell("scythe_04", "final", episodes(0)))
    reading = claim(runs, "succeeds")
    assert (reading.firmly, reading.on_the_means, reading.possibly) == (4, 4, 5) and reading.reading == "holds"
    runs[0][0] = cell("scythe_00", "final", episodes(0))
    assert claim(runs, "succeeds").reading == "could hold"


def test_the_claim_that_beats_sparse_ppo_reads_the_probability_of_improvement() -> None:
    finals = [cell(f"spade_0{i}", "final", episodes(20), "spade") for i in range(3)]
    sparse = [cell(f"spade_0{i}", "sparse_ppo", episodes(0), "spade") for i in range(3)]
    reading = claim({0: finals + sparse}, "beats sparse PPO", "spade")
    assert reading.reading == "holds" and reading.items == ["P(final > sparse_ppo) on 3"]
    level = [cell(f"spade_0{i}", "sparse_ppo", episodes(20), "spade") for i in range(3)]
    assert claim({0: finals + level}, "beats sparse PPO", "spade").reading == "does not hold"  # P = 0.5


def test_dense_ppo_is_comparable_when_it_succeeds_on_some_demonstration() -> None:
    finals = [cell(f"spade_0{i}", "final", episodes(20), "spade") for i in range(3)]
    dense = [cell("spade_00", "dense_ppo", episodes(17), "spade")]
    dense += [cell(f"spade_0{i}", "dense_ppo", episodes(2), "spade") for i in (1, 2)]
    reading = claim({0: finals + dense}, "dense PPO in some cases", "spade")
    assert reading.required == 1 and reading.on_the_means == 1 and reading.failing == ["spade_01", "spade_02"]
    assert reading.reading == "holds on the means"  # 0.85 over 20 episodes reaches below 0.8
    never = [cell(f"spade_0{i}", "dense_ppo", episodes(0), "spade") for i in range(3)]
    assert claim({0: finals + never}, "dense PPO in some cases", "spade").reading == "does not hold"


def test_lfd_is_comparable_when_the_final_policy_at_least_draws_with_it() -> None:
    finals = [cell(f"spade_0{i}", "final", episodes(20), "spade") for i in range(3)]
    lfd = [cell(f"spade_0{i}", "lfd", episodes(20), "spade") for i in range(3)]
    reading = claim({0: finals + lfd}, "LfD comparable", "spade")
    assert reading.reading == "holds" and reading.test == "P(final > lfd) >= 0.5"  # every pair a tie
    weaker = [cell(f"spade_0{i}", "final", episodes(4), "spade") for i in range(3)]
    reading = claim({0: weaker + lfd}, "LfD comparable", "spade")
    assert reading.reading == "does not hold" and reading.failing == ["P(final > lfd) on 3"]


def test_no_claim_is_read_without_what_it_needs() -> None:
    baseline_only = {0: [cell("scythe_00", "lfd", episodes(20))]}
    assert read_claims(summarise_cells(baseline_only), summarise_methods(baseline_only)) == []
    finals = {0: [cell("scythe_00", "final", episodes(20))]}  # no limits, no export, no baseline
    assert [r.claim for r in read_claims(summarise_cells(finals), summarise_methods(finals))] == ["succeeds"]


def test_the_open_loop_and_limits_claims_read_the_final_cells_exports_and_limits() -> None:
    def final(demo: str, exported_wins: int, past_limits: float) -> CellResult:
        won = np.asarray(episodes(exported_wins))
        exported = {"episodes": 20, "success_rate": won.mean(), "goal_reward": np.where(won, 10.0, 8.0).tolist()}
        limits = {
            "share_of_steps_past_limits": past_limits,
            "max_velocity_ratio": 0.95,
            "max_acceleration_ratio": 0.95,
            "share_of_steps_past_limits_per_episode": [past_limits] * 20,
        }
        return replace(
            cell(demo, "final", episodes(20), "spade"), exported=exported | {"successes": won.tolist()}, limits=limits
        )

    runs = {0: [final(f"spade_0{i}", 20, 0.0) for i in range(5)] + [final("spade_05", 2, 0.1)]}
    open_loop, limits = claim(runs, "open-loop", "spade"), claim(runs, "within limits", "spade")
    assert open_loop.required == 5 and open_loop.reading == "holds" and open_loop.failing == ["spade_05"]
    assert limits.required == 6 and limits.reading == "does not hold" and limits.failing == ["spade_05"]


def test_results_json_and_md_carry_the_claims(tmp_path: Path) -> None:
    runs = {0: [cell(f"scythe_0{i}", "final", episodes(20 if i < 2 else 2)) for i in range(3)]}
    write_results(tmp_path, runs, PRESET)
    (reading,) = json.loads((tmp_path / "results.json").read_text())["claims"]
    assert reading["claim"] == "succeeds" and reading["reading"] == "does not hold"
    assert reading["failing"] == ["scythe_02"]
    table = (tmp_path / "results.md").read_text()
    assert (
        "| succeeds | scythe | 3d | panda | final success >= 0.8 | 2 / 2 / 2, of 3 | 3 | **does not hold** | scythe_02 |"
        in table
    )
