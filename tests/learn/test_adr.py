"""Domain randomisation of the goal box: observation, the boundary-test rule on success, seeding, resume,
heat map and reach."""

from __future__ import annotations

import json
import xml.etree.ElementTree as ElementTree

import gymnasium as gym
import numpy as np
import pytest
import torch
from gymnasium.utils.env_checker import check_env

from toolimit.errors import InputError
from toolimit.learn import BatchedTaskVecEnv, TaskSimulator, ToolUseEnv, shipped_task
from toolimit.learn import adr as adr_module
from toolimit.learn import env as env_module
from toolimit.learn.adr import (
    DECISION_EPISODES,
    DELTA,
    HALF_RANGE,
    AdrBounds,
    AdrState,
    BoundaryBatch,
    boundary_test,
)
from toolimit.learn.adr_callback import AdrCallback
from toolimit.learn.heat_map import HeatMap, goal_box_heat_map
from toolimit.learn.ppo import CHECKPOINT_STATE
from toolimit.learn.training import CURVE_JSONL, LearningConfig, learn_policy, load_policy
from toolimit.scenes.base import WORLD_HALF_SIZE
from toolimit.viz.svg_heat_map import heat_map_svg

TINY = LearningConfig(timesteps=0, envs=2, preset="toolimit", clone_rollouts=2, clone_noise=0.3, clone_steps=20,
                      value_steps=20, checkpoint_every=1, seed=0, adr=True, adr_every=1)


def _parameters(model):
    return torch.cat([p.detach().flatten() for p in model.policy.parameters()]).numpy()


def test_observation_holds_each_instance_box_offset_in_tenths_of_a_metre(spade_task):
    simulator = TaskSimulator(spade_task, batch_size=4, adr=True)
    plain = TaskSimulator(spade_task, batch_size=4)
    aligned = spade_task.params["goal_position"][:2]
    observation = simulator.reset(np.random.default_rng(0))
    assert observation.shape == (4, plain.observation_size + 2) == (4, 3 + 4 + 3 + 1 + 2)
    np.testing.assert_array_equal(observation[:, -2:], 0.0)  # the bounds start at the aligned box: offset 0
    simulator.adr_bounds.low[0] -= 0.4
    observation = simulator.reset(np.random.default_rng(0))
    x = observation[:, -2]
    assert len(set(np.round(x, 5))) == 4, "one position per instance"
    assert np.all((x >= -4.0 - 1e-5) & (x <= 1e-5)) and x.min() < -1.0, "0.4 m below the aligned box is -4 units"
    np.testing.assert_allclose(x, (simulator.scene.goal_x - aligned[0]) / 0.1, atol=1e-5)  # where the boxes stand
    np.testing.assert_array_equal(observation[:, -1], 0.0)  # the planar box has no y: not randomised
    np.testing.assert_array_equal(observation[:, :-2], plain.reset(np.random.default_rng(0)))  # the rest as without ADR


def test_a_tool_without_goal_box_is_refused_in_one_line():
    with pytest.raises(InputError, match="the hammer scene has none") as error:
        TaskSimulator(shipped_task("hammer", "planar"), adr=True)
    assert "\n" not in str(error.value)


def test_adr_environments_pass_the_checkers(spade_task):
    env = ToolUseEnv("spade", "planar", adr=True)
    assert env.observation_space.shape == (13,)
    check_env(env, skip_render_check=True)
    made = gym.make("toolimit/SpadePlanar-v0", adr=True)
    observation, _ = made.reset(seed=1)
    assert made.observation_space.contains(observation)


def test_same_seed_same_draws(spade_task):
    def draws(seed: int, envs: int) -> np.ndarray:
        env = BatchedTaskVecEnv(spade_task, envs, seed=seed, adr=True)
        env.adr.bounds.low[0] -= 0.3
        return np.concatenate([env.reset()[:, -2] for _ in range(2)])

    np.testing.assert_array_equal(draws(3, 2), draws(3, 2))
    assert not np.array_equal(draws(3, 2), draws(4, 2))

    def picks(envs: int) -> list[tuple[str, str]]:
        state = BatchedTaskVecEnv(spade_task, envs, seed=5, adr=True).adr
        return [(t["axis"], t["side"]) for t in (boundary_test(state, _batch(8, 16)) for _ in range(6))]

    assert picks(2) == picks(4), "the tests' picks come from the ADR generator alone, whatever B"


def _state(axes=(0, 1), seed: int = 0) -> AdrState:
    return AdrState(AdrBounds.at(np.array([0.2, -0.1, 0.0]), axes), np.random.default_rng(seed))


def _batch(successes: int, episodes: int = DECISION_EPISODES):
    """A fake boundary test: ``successes`` of ``episodes`` succeed (the first ones)."""
    return lambda _: BoundaryBatch(np.arange(episodes) < successes, _placed(episodes), float(successes))


def _placed(episodes: int) -> np.ndarray:
    return np.ones(episodes, dtype=bool)


def _side(record) -> tuple[int, int]:
    return "xy".index(record["axis"]), ("low", "high").index(record["side"])


def test_a_bound_is_decided_only_once_its_buffer_holds_the_decision_episodes():
    """Batches of a quarter of the buffer, all successes: each bound moves out at its own every
    fourth test and not before; the other bounds' tests do not count towards it."""
    state, aligned = _state(), _state().bounds.aligned
    quarter = DECISION_EPISODES // 4
    seen = {}
    pinned_at = []

    def all_succeed(bounds: AdrBounds) -> BoundaryBatch:
        pinned_at.append((bounds.low.copy(), bounds.high.copy()))
        return BoundaryBatch(np.ones(quarter, dtype=bool), _placed(quarter), 20.0)

    for _ in range(40):
        record = boundary_test(state, all_succeed)
        key = _side(record)
        seen[key] = seen.get(key, 0) + 1
        if seen[key] % 4:
            assert record["decision"] is None and record["after"] == record["bound"], record
            assert len(state.buffers[key[0]][key[1]]) == quarter * (seen[key] % 4)
        else:
            assert record["decision"] == "push" and record["success_rate"] == 1.0, record
            assert record["after"] == pytest.approx(record["bound"] + (-DELTA, DELTA)[key[1]])
            assert state.buffers[key[0]][key[1]] == [], "a decision empties the buffer"
    low, high = pinned_at[0]
    axis, side = _side(state.tests[0])
    assert low[axis] == high[axis] == aligned[axis], "the batch pins the chosen coordinate at its bound"
    moved = sum(t["decision"] == "push" for t in state.tests)
    assert moved == sum(n // 4 for n in seen.values()) and moved > 0
    np.testing.assert_allclose((state.bounds.high - state.bounds.low).sum(), moved * DELTA)


def test_success_at_the_bound_pushes_it_at_0_8_pulls_it_at_0_2_and_holds_in_between():
    state = _state()
    aligned = state.bounds.aligned.copy()
    n = DECISION_EPISODES
    record = boundary_test(state, _batch(round(0.8 * n)))  # 26 of 32 = 0.81: out
    assert record["decision"] == "push" and abs(record["after"] - record["bound"]) == pytest.approx(DELTA)
    for _ in range(200):  # pushes stop at the paper's rectangle
        boundary_test(state, _batch(n))
    np.testing.assert_allclose(state.bounds.low, aligned - HALF_RANGE)
    np.testing.assert_allclose(state.bounds.high, aligned + HALF_RANGE)
    assert state.tests[-1]["decision"] == "hold", "at the rectangle a success cannot push further"
    for successes in (round(0.8 * n) - 1, n // 2, round(0.2 * n) + 1):  # 25, 16, 7 of 32: nothing moves
        record = boundary_test(state, _batch(successes))
        assert record["decision"] == "hold" and record["after"] == record["bound"], record
    record = boundary_test(state, _batch(round(0.2 * n)))  # 6 of 32 = 0.19: in
    assert record["decision"] == "pull" and record["success_rate"] == pytest.approx(6 / 32)
    assert abs(record["after"] - record["bound"]) == pytest.approx(DELTA)
    for _ in range(200):  # pulls stop at the aligned value
        boundary_test(state, _batch(0))
    np.testing.assert_allclose(state.bounds.low, aligned)
    np.testing.assert_allclose(state.bounds.high, aligned)
    assert len(state.tests) == 405


def test_a_buffer_mixes_its_batches_and_survives_a_checkpoint():
    """Half a buffer of successes, then half of failures at the same bound: 0.5, held. The same
    stream stopped after any test and resumed from the state dict gives the same records."""
    state = _state(axes=(0,))  # one coordinate: both batches land on x, the side is random
    half = DECISION_EPISODES // 2
    stream = [_batch(half, half), _batch(0, half)] * 20
    for fake in stream:
        boundary_test(state, fake)
    for stop in (1, 7, 20):
        resumed = _state(axes=(0,))
        for fake in stream[:stop]:
            boundary_test(resumed, fake)
        saved = json.loads(json.dumps(resumed.state_dict()))
        restored = _state(axes=(0,), seed=99)
        restored.load_state_dict(saved, "checkpoint.json")
        for fake in stream[stop:]:
            boundary_test(restored, fake)
        assert restored.tests == state.tests
        np.testing.assert_array_equal(restored.bounds.low, state.bounds.low)
    # each side's decisions: a buffer of one success batch and one failure batch is exactly 0.5
    rates = [t["success_rate"] for t in state.tests if t["decision"] is not None]
    assert rates and all(r in (0.0, 0.5, 1.0) for r in rates)
    assert 0.5 in rates


def test_same_seed_same_decisions_on_a_random_success_stream():
    def run(seed: int) -> list:
        state, stream = _state(seed=seed), np.random.default_rng(7)

        def noisy(_: AdrBounds) -> BoundaryBatch:
            return BoundaryBatch(stream.random(16) < 0.85, _placed(16), 0.0)

        for _ in range(60):
            boundary_test(state, noisy)
        return state.tests

    assert run(3) == run(3)
    assert run(3) != run(4)


def test_a_bound_is_not_pushed_where_the_box_cannot_stand_and_planar_moves_x_only():
    state = _state(axes=(0, 2))
    only_at_the_aligned_box = lambda bounds: np.array_equal(bounds.low, bounds.aligned)  # noqa: E731
    record = boundary_test(state, _batch(DECISION_EPISODES), placeable=only_at_the_aligned_box)
    assert record["axis"] == "x" and record["after"] == record["bound"] and record["decision"] == "hold"
    for _ in range(50):
        boundary_test(state, _batch(DECISION_EPISODES))
    assert state.bounds.low[1] == state.bounds.high[1] == -0.1


def test_an_unplaceable_bound_is_re_picked_from_the_same_generator_or_the_test_skipped():
    """x low refused (as the near x bound whose whole y range stands on the deposit): its tests go
    to another bound, never run there, its buffer stays empty; the same seed re-picks alike; with
    every bound refused the test is skipped without episodes. The record counts both."""

    def run(seed: int) -> AdrState:
        state = _state(seed=seed)
        state.bounds.low[0] -= 0.2  # x low apart from the aligned value, so the pin identifies it
        ran_at = []

        def at_x_low(bounds: AdrBounds) -> bool:
            return bool(bounds.low[0] == bounds.high[0] == state.bounds.bound(0, 0))

        def batch(bounds: AdrBounds) -> BoundaryBatch:
            ran_at.append(at_x_low(bounds))
            return _batch(8, 16)(bounds)

        for _ in range(40):
            boundary_test(state, batch, lambda bounds: not at_x_low(bounds))
        assert not any(ran_at), "no batch ran with x pinned at its low bound"
        return state

    state = run(0)
    repicked = [t for t in state.tests if t["refused"]]
    assert repicked and all(t["refused"] == ["x low"] and t["skipped"] is None for t in repicked)
    assert all((t["axis"], t["side"]) != ("x", "low") for t in state.tests)
    assert state.buffers[0][0] == [] and state.bounds.bound(0, 0) == pytest.approx(0.0)
    assert len(repicked) < len(state.tests), "a first pick elsewhere is not re-picked"
    record = state.record(every=8)
    assert record["repicked"] == len(repicked) and record["skipped"] == 0
    assert run(0).tests == state.tests and run(1).tests != state.tests

    skipped = _state()
    record = boundary_test(skipped, lambda _: pytest.fail("no episodes for a skipped test"), lambda _: False)
    assert record["skipped"] and record["episodes"] == 0 and record["decision"] is None
    assert sorted(record["refused"]) == ["x high", "x low", "y high", "y low"]
    assert skipped.record(every=8)["skipped"] == 1 and skipped.record(every=8)["repicked"] == 0
    np.testing.assert_array_equal(skipped.bounds.low, skipped.bounds.aligned)


def test_episodes_not_placed_at_the_bound_never_join_its_buffer():
    """Half of each batch fell back to the aligned box (and succeeded there): only the placed half,
    all failures, counts, so the bound is pulled at 0.0 rather than held at 0.5."""
    state = _state(axes=(0,))
    state.bounds.low[0] -= 0.2
    state.bounds.high[0] += 0.2
    half = DECISION_EPISODES // 2
    fell_back = np.arange(2 * half) < half

    def batch(_: AdrBounds) -> BoundaryBatch:
        return BoundaryBatch(successes=fell_back, placed=~fell_back, goal_reward_mean=0.0)

    records = [boundary_test(state, batch) for _ in range(4)]
    assert all(r["episodes"] == 2 * half and r["placed"] == half and r["successes"] == 0 for r in records)
    decided = [r for r in records if r["decision"] is not None]
    assert decided and all(r["decision"] == "pull" and r["success_rate"] == 0.0 for r in decided)
    assert state.record(every=8)["unplaced_episodes"] == 4 * half


def test_the_simulator_says_which_boxes_fell_back_and_the_callback_never_tests_there(spade_task, cloned_adr_policy):
    """Planar spade: the deposit lies beyond the aligned box in x. A high x bound on the deposit is
    refused by the callback's placeability check, so its tests run at x low; a batch pinned there
    anyway reports every box as not placed (they stand at the aligned one)."""
    env = BatchedTaskVecEnv(spade_task, 2, seed=0, adr=True)
    aligned = env.adr.bounds.aligned[0]
    env.adr.bounds.low[0], env.adr.bounds.high[0] = aligned - 0.2, aligned + 0.1  # 0.02 m on is on the deposit
    callback = AdrCallback(env)
    callback.init_callback(cloned_adr_policy)
    on_deposit = callback._episodes_at(env.adr.bounds.pinned(0, 1))
    assert not on_deposit.placed.any()
    np.testing.assert_allclose(callback.simulator.box_positions[:, 0], aligned)
    assert callback._episodes_at(env.adr.bounds.pinned(0, 0)).placed.all()
    records = [boundary_test(env.adr, callback._episodes_at, callback._placeable) for _ in range(8)]
    assert all(r["side"] == "low" and r["placed"] == r["episodes"] == 2 for r in records)
    assert any(r["refused"] == ["x high"] for r in records), "seed 0 first picks x high at least once in 8"
    assert env.adr.buffers[0][1] == []
    env.close()


def test_a_checkpoint_of_an_earlier_adr_rule_is_refused_in_one_line(spade_task, tmp_path):
    out = tmp_path / "run"
    first = LearningConfig(**{**TINY.__dict__, "timesteps": spade_task.horizon * 2})
    learn_policy(spade_task, out, first, progress=False)
    state_path = out / CHECKPOINT_STATE
    state = json.loads(state_path.read_text())
    del state["adr"]["rule_version"], state["adr"]["buffers"]  # as the return rule wrote it
    state_path.write_text(json.dumps(state))
    more = LearningConfig(**{**TINY.__dict__, "timesteps": spade_task.horizon * 4})
    with pytest.raises(InputError, match="written by an earlier ADR rule") as error:
        learn_policy(spade_task, out, more, progress=False)
    assert str(state_path) in str(error.value) and "new output folder" in str(error.value)
    assert "\n" not in str(error.value)


def test_learning_logs_and_resumes_the_adr_state_exactly(spade_task, tmp_path, monkeypatch):
    """Every test pushes (threshold lowered, one batch a decision), so bounds move and the
    environment is reset in between; three updates in one go, or one, a stop and the rest: same
    network, same bounds and tests."""
    monkeypatch.setattr(adr_module, "PUSH_SUCCESS", 0.0)
    monkeypatch.setattr(adr_module, "DECISION_EPISODES", TINY.envs)
    per_update = spade_task.horizon * 2
    three = LearningConfig(**{**TINY.__dict__, "timesteps": 3 * per_update})
    whole = learn_policy(spade_task, tmp_path / "whole", three, progress=False)
    learn_policy(spade_task, tmp_path / "split", LearningConfig(**{**TINY.__dict__, "timesteps": per_update}),
                 progress=False)
    resumed = learn_policy(spade_task, tmp_path / "split", three, progress=False)
    assert resumed.record["resumed"]
    np.testing.assert_allclose(_parameters(resumed.model), _parameters(whole.model), rtol=0, atol=1e-6)
    assert resumed.record["adr"] == whole.record["adr"]
    tests = whole.record["adr"]["tests"]
    assert len(tests) == 2  # before updates 2 and 3
    assert all(t["episodes"] == TINY.envs and t["decision"] in ("push", "hold") for t in tests)
    # x grows away from the deposit only: 0.05 m towards it, the box would stand on it
    assert whole.record["adr"]["range_m"][0] == pytest.approx(DELTA * sum(t["side"] == "low" for t in tests))
    assert whole.record["adr"]["range_m"][0] > 0, "seed 0 pushes once, so the environment is reset mid-run"
    curves = [[json.loads(line) for line in (tmp_path / name / CURVE_JSONL).read_text().splitlines()]
              for name in ("whole", "split")]
    assert curves[0] == [c | {"approx_kl": curves[0][k]["approx_kl"]} for k, c in enumerate(curves[1])]
    assert curves[0][0]["adr_low"] == curves[0][0]["adr_high"] == whole.record["adr"]["aligned"]
    saved = json.loads((tmp_path / "whole" / "learning.json").read_text())["adr"]
    assert saved["adr_low"] == whole.record["adr"]["adr_low"] and saved["every"] == 1
    assert saved["rule"]["push_success"] == 0.0 and saved["rule"]["pull_success"] == adr_module.PULL_SUCCESS


def test_reachable_cells_are_those_within_the_reach_circle_and_only_they_count():
    """A 3 x 3 map around a base at the origin with a reach of 1 m: the corners (1.41 m) are out."""
    edges = np.array([-1.5, -0.5, 0.5, 1.5])
    successes = np.array([[1.0, 1.0, 1.0], [0.0, 1.0, np.nan], [1.0, 0.25, 1.0]])
    heat_map = HeatMap(
        x_edges=edges, y_edges=edges, goal_rewards=successes * 20, successes=successes,
        aligned=np.zeros(2), rectangle=np.array([[-1.0, -1.0], [1.0, 1.0]]), base=np.zeros(2), reach=1.0,
        deposit=np.zeros(5), episodes=4, observes_box=True,
    )
    np.testing.assert_array_equal(heat_map.reachable, [[False, True, False], [True, True, True], [False, True, False]])
    counts = heat_map.counts()
    assert counts["standing_in_rectangle"] == 8 and counts["succeeding_in_rectangle"] == 6
    assert counts["standing_reachable_in_rectangle"] == 4, "the NaN cell and the four corners left out"
    assert counts["succeeding_reachable_in_rectangle"] == 2, "(0, 1) and the centre; (1, 0) failed, (1, 2) 0.25"
    assert heat_map.record()["reachable"][0] == [False, True, False]
    root = ElementTree.fromstring(heat_map_svg(heat_map, "reach"))
    struck = [e for e in root.iter("{http://www.w3.org/2000/svg}path") if e.get("class") == "unreachable"]
    assert len(struck) == 4


@pytest.fixture(scope="module")
def cloned_adr_policy(spade_task, tmp_path_factory):
    """Cloned (no PPO) from 4 tracking rollouts at the aligned box, observing it."""
    config = LearningConfig(**{**TINY.__dict__, "clone_rollouts": 4, "clone_steps": 1500, "value_steps": 0})
    return learn_policy(spade_task, tmp_path_factory.mktemp("adr_policy"), config, progress=False).model


def test_the_clone_starts_blind_to_the_box(spade_task, cloned_adr_policy):
    """After cloning, the first layer's weights on the box offset are 0 in both networks (the others
    not), so the clone's action and value at the aligned box (offset 0, where it was cloned) are
    its action and value wherever the box stands."""
    extractor = cloned_adr_policy.policy.mlp_extractor
    for network in (extractor.policy_net, extractor.value_net):
        assert torch.count_nonzero(network[0].weight[:, -2:]) == 0
        assert torch.count_nonzero(network[0].weight[:, :-2]) > 0
    at_aligned = TaskSimulator(spade_task, batch_size=2, adr=True).reset(np.random.default_rng(0))
    elsewhere = at_aligned.copy()
    elsewhere[:, -2] = [-3.0, 2.5]

    def output(observation: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        action, _ = cloned_adr_policy.predict(observation, deterministic=True)
        with torch.no_grad():
            return action, cloned_adr_policy.policy.predict_values(torch.as_tensor(observation)).numpy()

    for ours, theirs in zip(output(at_aligned), output(elsewhere), strict=True):
        np.testing.assert_array_equal(ours, theirs)


def test_a_policy_that_observed_the_box_in_world_metres_is_refused_in_one_line(spade_task, tmp_path, monkeypatch):
    """An ADR policy learned before rule 3 has the box in +-5 m in its observation space."""
    monkeypatch.setattr(env_module, "BOX_OFFSET_BOUND", WORLD_HALF_SIZE)
    learn_policy(spade_task, tmp_path, TINY, progress=False)
    monkeypatch.undo()
    with pytest.raises(InputError, match="observes the goal box in world metres") as error:
        load_policy(tmp_path)
    assert str(tmp_path / "policy.safetensors") in str(error.value) and "\n" not in str(error.value)


def test_heat_map_values_come_from_rollouts_and_the_svg_has_one_cell_per_grid_point(spade_task, cloned_adr_policy):
    heat_map = goal_box_heat_map(cloned_adr_policy, spade_task, grid=3, seed=0)
    assert heat_map.goal_rewards.shape == (1, 3), "the planar box has no y: one row"
    left, middle, right = heat_map.goal_rewards[0]
    np.testing.assert_allclose(heat_map.centres[0][1], spade_task.params["goal_position"][0])
    assert middle >= 10 and middle > left, heat_map.goal_rewards  # aligned box filled, far corner not
    assert np.isnan(right), "0.75 m towards the deposit the box would stand on it"
    assert heat_map.observes_box and 0.5 < heat_map.reach < 2.0
    root = ElementTree.fromstring(heat_map_svg(heat_map, "test"))
    cells = [e for e in root.iter("{http://www.w3.org/2000/svg}rect") if e.get("class") == "cell"]
    assert len(cells) == heat_map.goal_rewards.size
    assert heat_map.record()["goal_rewards"][0][2] is None
    # the grid spans 1.5 x the rectangle: the outer cells (0.75 m from the aligned box) lie outside it
    succeeded = int(heat_map.successes[0, 1] >= 0.5) + int(heat_map.successes[0, 0] >= 0.5)
    middle_reachable = bool(heat_map.reachable[0, 1])
    assert heat_map.counts() == {
        "standing": 2,
        "succeeding": succeeded,
        "standing_in_rectangle": 1,
        "succeeding_in_rectangle": int(heat_map.successes[0, 1] >= 0.5),
        "standing_reachable_in_rectangle": int(middle_reachable),
        "succeeding_reachable_in_rectangle": int(middle_reachable and heat_map.successes[0, 1] >= 0.5),
    }
