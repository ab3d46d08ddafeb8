"""The alignment search: sample, replay, keep the first K samples that earn a goal reward in at least
``accept_replays`` of their replays.

Every sample i draws from its own generator ``np.random.default_rng([seed, i])`` and resets the
scene from it, so a sample's outcome depends only on (seed, i). Worker processes evaluate chunks
of consecutive indices and the parent merges them in index order, stopping once the index-ordered
prefix holds K candidates: the result is the same whatever the number of workers.
"""

from __future__ import annotations

import contextlib
import functools
import re
import time
from collections.abc import Callable, Generator, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from toolimit.align.checkpoint import checkpoint_key, load_checkpoint, save_checkpoint
from toolimit.align.config import AlignmentConfig, demo_plane
from toolimit.align.episode_cut import EpisodeCut, first_reward_cut, is_timed
from toolimit.align.keypoints import velocity_keypoints
from toolimit.align.sampler import (
    AlignmentSample,
    apply_alignment_sample,
    draw_alignment_sample,
    minimum_element_distance,
)
from toolimit.demos.cleaning import CleaningReport, clean_demo
from toolimit.demos.tool_demo import ToolDemo
from toolimit.distributed import Cluster, RayTarget, ray_cluster
from toolimit.errors import InputError, InvalidSceneParameters
from toolimit.interrupts import Interrupted, interruptible
from toolimit.progress import progress_bar
from toolimit.scenes.base import ParameterSpec, Scene
from toolimit.scenes.registry import make_scene
from toolimit.scenes.replay import replay, speed_limited
from toolimit.tools import ToolPose, tool_spec
from toolimit.workers import ordered_results

SceneFactory = Callable[[], Scene]

#: Seconds between checkpoint writes.
CHECKPOINT_EVERY_S = 5.0


@dataclass(frozen=True)
class Candidate:
    """A sample accepted by the search: at least ``config.accept_replays`` of its replays earned a goal
    reward.

    Attributes:
        index: the sample's index (its generator is ``default_rng([seed, index])``).
        reward: mean final goal reward over the replays.
        replay_rewards: (replays,) final goal reward of each replay.
        sample: the drawn scale, z offset, rolls and scene parameters.
        cut: where the episode lies in the aligned motion, for a scene whose goal is timed
            (:mod:`toolimit.align.episode_cut`); None otherwise (the whole motion).
    """

    index: int
    reward: float
    replay_rewards: np.ndarray
    sample: AlignmentSample
    cut: EpisodeCut | None = None


@dataclass(frozen=True)
class Rejected:
    """A sample the sampler or the scene refused; ``reason`` says why."""

    index: int
    reason: str


@dataclass(frozen=True)
class Unaccepted:
    """A sample replayed but not accepted: fewer than ``config.accept_replays`` of its runs earned a
    goal reward; ``replay_rewards`` (runs,) (the screening runs only, when they earned nothing)."""

    index: int
    replay_rewards: np.ndarray

    @property
    def reward(self) -> float:
        return float(np.mean(self.replay_rewards))


#: What happened to one sample.
SampleOutcome = Rejected | Unaccepted | Candidate


@dataclass
class AlignmentResult:
    """The search's outcome.

    Attributes:
        tool, world: the scene aligned to.
        plane: the plane the demo was projected on ("xz", "xy") or None (3D).
        seed: the search's seed.
        config: the settings used.
        demo: the demonstration as replayed before a sample's transform: resampled to the scene's
            control rate and projected to ``plane``; world frame, metres.
        keypoints: (K,) frame indices of ``demo``.
        min_distance: d_th between scene elements, metres.
        candidates: the first ``config.candidates`` candidates in sample-index order.
        samples_tried: samples in the index-ordered prefix the search examined.
        samples_rejected: of those, samples the sampler or the scene rejected.
        samples_to_first_candidate: index of the first candidate + 1, None if none.
        rejection_reasons: rejected samples per reason (its message with numbers replaced by '#').
        wall_time_s: seconds the search took, worker start-up included (summed over resumed runs).
        cleaning: what :func:`~toolimit.demos.clean_demo` changed in the demo before the search,
            None when the demo was aligned as given (``clean=False``).
    """

    tool: str
    world: str
    plane: str | None
    seed: int
    config: AlignmentConfig
    demo: ToolDemo
    keypoints: np.ndarray
    min_distance: float
    candidates: list[Candidate] = field(default_factory=list)
    samples_tried: int = 0
    samples_rejected: int = 0
    samples_to_first_candidate: int | None = None
    rejection_reasons: dict[str, int] = field(default_factory=dict)
    wall_time_s: float = 0.0
    cleaning: CleaningReport | None = None

    @property
    def best(self) -> Candidate | None:
        """The candidate with the highest mean reward (the earliest among equals), None if none."""
        if not self.candidates:
            return None
        return max(self.candidates, key=lambda c: (c.reward, -c.index))

    def aligned_motion(self, candidate: Candidate) -> tuple[ToolDemo, np.ndarray, ToolPose]:
        """The candidate's aligned demo, per-frame roll (T,) rad and tool poses in the world frame:
        the whole motion (see :meth:`episode_poses` for the episode the later stages use)."""
        return apply_alignment_sample(self.demo, self.keypoints, candidate.sample)

    def episode_poses(self, candidate: Candidate) -> ToolPose:
        """The tool poses of the candidate's episode, world frame: the aligned motion as the tool
        alone reached it in its replays (within the tool speed limit,
        :func:`~toolimit.scenes.replay.speed_limited`; the authors kept these reached poses as the
        robot's targets), cut by the authors' rule for a timed goal (``candidate.cut``), the whole
        of it otherwise."""
        poses = speed_limited(
            self.aligned_motion(candidate)[2], 1.0 / self.demo.fps, tool_spec(self.tool).steered_offset
        )
        if candidate.cut is None:
            return poses
        return ToolPose(candidate.cut.apply(poses.position), candidate.cut.apply(poses.rotation))

    def replay_generator(self, candidate: Candidate, parameters: Sequence[ParameterSpec]) -> np.random.Generator:
        """The candidate's generator as the search left it after drawing the sample: a scene reset
        from it (with the scene's ``parameters``) replays the search's first run of that sample."""
        rng = np.random.default_rng([self.seed, candidate.index])
        draw_alignment_sample(
            self.demo,
            self.keypoints,
            parameters,
            self.config,
            self.config.element_covariance(self.plane),
            self.min_distance,
            rng,
            plane=self.plane,
        )
        return rng


def prepare_demo(demo: ToolDemo, tool: str, world: str, control_dt: float) -> tuple[ToolDemo, str | None]:
    """The demo at the scene's control rate (1 / control_dt fps), projected onto the world's plane."""
    fps = 1.0 / control_dt
    if not np.isclose(demo.fps, fps):
        demo = demo.resampled(fps)
    plane = demo_plane(tool, world)
    if plane is not None:
        demo = demo.projected_to_plane(plane)
    return demo, plane


class SampleEvaluator:
    """Draws and replays samples in one scene (one per process)."""

    def __init__(
        self,
        scene: Scene,
        demo: ToolDemo,
        keypoints: np.ndarray,
        config: AlignmentConfig,
        plane: str | None,
        min_distance: float,
        seed: int,
    ) -> None:
        self.scene = scene
        self.demo = demo
        self.keypoints = keypoints
        self.config = config
        self.plane = plane
        self.covariance = config.element_covariance(plane)
        self.min_distance = min_distance
        self.seed = seed

    def draw(self, rng: np.random.Generator) -> AlignmentSample | None:
        """A sample from ``rng`` (the sample's own generator), None if its elements cannot be placed."""
        return draw_alignment_sample(
            self.demo,
            self.keypoints,
            self.scene.parameters,
            self.config,
            self.covariance,
            self.min_distance,
            rng,
            plane=self.plane,
        )

    def evaluate(self, index: int) -> SampleOutcome:
        """Draw sample ``index`` from ``default_rng([seed, index])``, check it, replay it.

        The same generator then resets the scene (screening runs first, if any), so the outcome
        depends only on (seed, index).
        """
        rng = np.random.default_rng([self.seed, index])
        sample = self.draw(rng)
        if sample is None:
            return Rejected(index, "sampler: elements closer than the minimum distance")
        reason = self.scene.invalid_reason(sample.params)
        if reason is not None:
            return Rejected(index, reason)
        aligned, _, poses = apply_alignment_sample(self.demo, self.keypoints, sample)
        depth = -aligned.head[:, 2].min()
        if depth > self.config.ground_tolerance:
            return Rejected(index, f"sampler: the tool head goes {depth:.3f} m below the ground")
        try:
            if self.config.screen_replays > 0:
                screened = replay(self.scene, sample.params, rng, poses, self.config.screen_replays)
                if not np.any(screened != 0.0):
                    return Unaccepted(index, screened)
            trace: list[np.ndarray] = []  # (B,) goal rewards after each step, for a timed goal's cut
            record = (lambda _, scene: trace.append(np.array(scene.goal_reward()))) if is_timed(self.scene) else None
            rewards = replay(self.scene, sample.params, rng, poses, self.config.replays, on_step=record)
        except InvalidSceneParameters as error:
            return Rejected(index, str(error))
        if np.count_nonzero(rewards > 0.0) < self.config.accept_replays:
            return Unaccepted(index, rewards)
        return Candidate(
            index, float(np.mean(rewards)), rewards, sample, first_reward_cut(np.array(trace)) if trace else None
        )

    def evaluate_range(self, start: int, stop: int) -> list[SampleOutcome]:
        return [self.evaluate(index) for index in range(start, stop)]


#: The evaluator of a worker process, built once by :func:`_init_worker`.
_WORKER_EVALUATOR: SampleEvaluator | None = None


def _init_worker(scene_factory: SceneFactory, *evaluator_args: object) -> None:
    global _WORKER_EVALUATOR
    _WORKER_EVALUATOR = SampleEvaluator(scene_factory(), *evaluator_args)  # type: ignore[arg-type]


def _evaluate_range_in_worker(start: int, stop: int) -> list[SampleOutcome]:
    assert _WORKER_EVALUATOR is not None, "worker not initialised"
    return _WORKER_EVALUATOR.evaluate_range(start, stop)


def _chunks(first: int, total: int, size: int) -> Iterator[tuple[int, int]]:
    for start in range(first, total, size):
        yield start, min(start + size, total)


def _outcomes_in_order(
    evaluator: SampleEvaluator,
    scene_factory: SceneFactory,
    config: AlignmentConfig,
    workers: int,
    first: int,
    on_ray: bool = False,
) -> Generator[list[SampleOutcome], None, None]:
    """Chunks of outcomes in index order from sample ``first``; the consumer stops when it has enough
    (closing this generator ends the worker processes, or the Ray actors with ``on_ray``)."""
    chunks = _chunks(first, config.samples, config.chunk_size)
    if workers == 1 and not on_ray:
        for start, stop in chunks:
            yield evaluator.evaluate_range(start, stop)
        return
    init_args = (
        scene_factory,
        evaluator.demo,
        evaluator.keypoints,
        evaluator.config,
        evaluator.plane,
        evaluator.min_distance,
        evaluator.seed,
    )
    yield from ordered_results(_evaluate_range_in_worker, chunks, workers, _init_worker, init_args, on_ray)


def align(
    demo: ToolDemo,
    tool: str,
    world: str,
    config: AlignmentConfig | None = None,
    seed: int = 0,
    workers: int = 1,
    progress: bool = True,
    scene_factory: SceneFactory | None = None,
    checkpoint: str | Path | None = None,
    clean: bool = True,
    ray: RayTarget = False,
) -> AlignmentResult:
    """Search scene parameters, scale, z offset and rolls under which ``demo`` reaches the goal.

    Args:
        demo: the demonstration (world frame, metres), any frame rate. It is cleaned first
            (:func:`~toolimit.demos.clean_demo`: reconstruction outliers replaced, jitter smoothed)
            unless ``clean=False``, as ``toolimit align`` does unless ``--no-clean``.
        tool, world: the scene, built with :func:`toolimit.scenes.registry.make_scene`.
        config: search settings (default :class:`AlignmentConfig`).
        seed: sample i uses ``np.random.default_rng([seed, i])``.
        workers: processes evaluating samples; the result does not depend on it.
        progress: show a progress bar of the candidates found against K, with the samples examined.
        scene_factory: a picklable callable making the scene instead of the registry (tests,
            researchers' own scenes); every worker calls it once.
        clean: clean the demo before the search (default True; the report is ``result.cleaning``).
        ray: batches of samples (``config.chunk_size`` each) as tasks on a Ray cluster
            (:data:`~toolimit.distributed.RayTarget`), one actor per CPU, instead of ``workers``
            local processes; the candidates are the same.
        checkpoint: a JSON file where the search saves its progress (every few seconds, and when
            interrupted) and from which it resumes when the file was made with the same demo,
            scene, seed and settings; it is removed when the search ends.

    Raises InputError for a demonstration of another tool, and :class:`SearchInterrupted` (a KeyboardInterrupt) on SIGINT or SIGTERM, after saving the
    checkpoint (if any sample finished) and ending the worker processes; a second signal during
    that cleanup is ignored.

    The demo is resampled to the scene's control rate and projected onto the world's plane
    (:func:`~toolimit.align.config.demo_plane`); keypoints and the minimum element distance d_th
    come from that prepared demo's head path. Workers are started with the "spawn" method: a
    script calling ``align(..., workers > 1)`` needs the ``if __name__ == "__main__":`` guard.
    """
    config = config or AlignmentConfig()
    if not (isinstance(workers, int) and workers >= 1):
        raise InputError(f"workers: expected a positive integer, got {workers!r}")
    if demo.tool != tool:
        raise InputError(f"the demonstration shows the {demo.tool}, not the {tool}: align it in a {demo.tool} scene")
    started = time.perf_counter()
    cleaning = None
    if clean:
        demo, cleaning = clean_demo(demo)
    scene_factory = scene_factory or functools.partial(make_scene, tool, world)
    scene = scene_factory()
    prepared, plane = prepare_demo(demo, tool, world, scene.control_dt)
    keypoints = velocity_keypoints(prepared, config.keypoint_fraction)
    min_distance = minimum_element_distance(prepared.head)
    evaluator = SampleEvaluator(scene, prepared, keypoints, config, plane, min_distance, seed)
    result = AlignmentResult(tool, world, plane, seed, config, prepared, keypoints, min_distance, cleaning=cleaning)
    key = checkpoint_key(tool, world, seed, config, prepared)
    previous_time = 0.0
    if checkpoint is not None and (state := load_checkpoint(checkpoint, key)) is not None:
        previous_time = _restore(result, state, evaluator)
    with ray_cluster(ray) if ray else contextlib.nullcontext() as cluster:
        _search(result, evaluator, scene_factory, workers, progress, checkpoint, key, previous_time, started, cluster)
    result.wall_time_s = previous_time + time.perf_counter() - started
    if checkpoint is not None:
        Path(checkpoint).unlink(missing_ok=True)
    return result


def _search(
    result: AlignmentResult,
    evaluator: SampleEvaluator,
    scene_factory: SceneFactory,
    workers: int,
    progress: bool,
    checkpoint: str | Path | None,
    key: dict[str, Any],
    previous_time: float,
    started: float,
    cluster: Cluster | None,
) -> None:
    """Merge outcomes into ``result`` until it holds K candidates or the budget ends (see :func:`align`)."""
    config = result.config
    # the search ends at the K-th candidate, usually long before the sample budget: count candidates
    bar = progress_bar(
        total=config.candidates,
        initial=len(result.candidates),
        desc=f"align {result.tool}/{result.world}" + ("" if cluster is None else f" on {cluster.summary()}"),
        unit="candidate",
        disable=not progress,
    )
    last_save = time.perf_counter()
    chunks = _outcomes_in_order(
        evaluator, scene_factory, config, workers, first=result.samples_tried, on_ray=cluster is not None
    )
    with interruptible():
        try:
            with bar, contextlib.closing(chunks):  # closing the generator ends the worker processes
                for outcomes in chunks:
                    enough = _merge(result, outcomes)
                    bar.set_postfix(
                        samples=f"{result.samples_tried}/{config.samples}",
                        rejected=result.samples_rejected,
                        refresh=False,
                    )
                    bar.update(len(result.candidates) - bar.n)
                    if enough:
                        break
                    if checkpoint is not None and time.perf_counter() - last_save > CHECKPOINT_EVERY_S:
                        result.wall_time_s = previous_time + time.perf_counter() - started
                        save_checkpoint(checkpoint, key, _state(result))
                        last_save = time.perf_counter()
        except Interrupted as stop:
            saved = None
            if checkpoint is not None and result.samples_tried > 0:
                result.wall_time_s = previous_time + time.perf_counter() - started
                save_checkpoint(checkpoint, key, _state(result))
                saved = Path(checkpoint)
            raise SearchInterrupted(stop.signum, result.samples_tried, len(result.candidates), saved) from None


class SearchInterrupted(Interrupted):
    """The search stopped on SIGINT or SIGTERM, its worker processes ended.

    Attributes: ``samples_tried`` (the index-ordered prefix examined), ``candidates`` (found in it),
    ``checkpoint`` (the file holding that progress, None when nothing was saved: no checkpoint
    asked for, or no sample finished).
    """

    def __init__(self, signum: int, samples_tried: int, candidates: int, checkpoint: Path | None) -> None:
        super().__init__(signum)
        self.samples_tried = samples_tried
        self.candidates = candidates
        self.checkpoint = checkpoint


def _state(result: AlignmentResult) -> dict[str, Any]:
    """The search's progress as JSON values (see :mod:`toolimit.align.checkpoint`)."""
    return {
        "samples_tried": result.samples_tried,
        "samples_rejected": result.samples_rejected,
        "samples_to_first_candidate": result.samples_to_first_candidate,
        "rejection_reasons": result.rejection_reasons,
        "wall_time_s": result.wall_time_s,
        "candidates": [
            {
                "index": c.index,
                "replay_rewards": c.replay_rewards.tolist(),
                "first_reward_frame": None if c.cut is None else c.cut.first_reward_frame,
            }
            for c in result.candidates
        ],
    }


def _restore(result: AlignmentResult, state: dict[str, Any], evaluator: SampleEvaluator) -> float:
    """Set ``result`` to a checkpoint's progress (candidate samples re-drawn); returns its time, s."""
    result.samples_tried = int(state["samples_tried"])
    result.samples_rejected = int(state["samples_rejected"])
    result.samples_to_first_candidate = state["samples_to_first_candidate"]
    result.rejection_reasons = {str(k): int(v) for k, v in state["rejection_reasons"].items()}
    for saved in state["candidates"]:
        index = int(saved["index"])
        sample = evaluator.draw(np.random.default_rng([result.seed, index]))
        assert sample is not None, f"checkpoint candidate {index} no longer draws a sample"
        rewards = np.asarray(saved["replay_rewards"], dtype=float)
        first = saved.get("first_reward_frame")
        cut = None if first is None else EpisodeCut(int(first))
        result.candidates.append(Candidate(index, float(np.mean(rewards)), rewards, sample, cut))
    return float(state["wall_time_s"])


#: Numbers in a rejection message, replaced by '#' so that reasons of one kind count together.
_NUMBER = re.compile(r"[-+]?\d+(?:\.\d*)?(?:[eE][-+]?\d+)?")


def _merge(result: AlignmentResult, outcomes: list[SampleOutcome]) -> bool:
    """Add a chunk's outcomes (in index order) to ``result``; True once it holds K candidates."""
    for outcome in outcomes:
        result.samples_tried = outcome.index + 1
        if isinstance(outcome, Rejected):
            result.samples_rejected += 1
            reason = _NUMBER.sub("#", outcome.reason)
            result.rejection_reasons[reason] = result.rejection_reasons.get(reason, 0) + 1
        elif isinstance(outcome, Candidate):
            result.candidates.append(outcome)
            if result.samples_to_first_candidate is None:
                result.samples_to_first_candidate = outcome.index + 1
            if len(result.candidates) >= result.config.candidates:
                return True
    return False
