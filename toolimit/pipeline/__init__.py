"""The pipeline as library code: each stage a function of the previous stage's output and its
typed settings, and :func:`run_pipeline` chaining them with resume::

    from toolimit.pipeline import PipelineSettings, run_pipeline

    result = run_pipeline("data/demos/spade_03.npz", "runs/spade", tool="spade", robot="planar3",
                          world="planar", settings=PipelineSettings.for_world("planar"))
    result.success_rate

The settings (:mod:`.settings`) are the one place each default is written; the ``toolimit``
command's flags are built from them.
"""

from toolimit.pipeline.run import RUN_JSON, STAGES, PipelineResult, run_pipeline
from toolimit.pipeline.settings import (
    QUICK,
    WORLD_PRESETS,
    AlignSettings,
    EvaluationSettings,
    ExportSettings,
    PipelineSettings,
    TrajoptSettings,
)
from toolimit.pipeline.stages import (
    EVALUATION_JSON,
    PolicyEvaluation,
    TrajectoryStage,
    align_stage,
    evaluate_stage,
    export_stage,
    learn_stage,
    trajopt_from_poses,
    trajopt_stage,
)

__all__ = [
    "EVALUATION_JSON",
    "QUICK",
    "RUN_JSON",
    "STAGES",
    "WORLD_PRESETS",
    "AlignSettings",
    "EvaluationSettings",
    "ExportSettings",
    "PipelineResult",
    "PipelineSettings",
    "PolicyEvaluation",
    "TrajectoryStage",
    "TrajoptSettings",
    "align_stage",
    "evaluate_stage",
    "export_stage",
    "learn_stage",
    "run_pipeline",
    "trajopt_from_poses",
    "trajopt_stage",
]
