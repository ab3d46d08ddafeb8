"""Every command's flags start from its settings: a flag left out keeps the settings' default."""

from __future__ import annotations

import dataclasses

import pytest

from toolimit.cli import build_parser
from toolimit.cli.align import ALIGN_FLAGS
from toolimit.cli.evaluate import EVALUATION_FLAGS
from toolimit.cli.export import EXPORT_FLAGS
from toolimit.cli.flags import Flag, apply_flags, field_help
from toolimit.cli.learn import LEARNING_FLAGS, learning_config
from toolimit.cli.run import RUN_FLAGS, pipeline_settings
from toolimit.cli.trajopt import TRAJOPT_FLAGS
from toolimit.learn.training import LearningConfig
from toolimit.pipeline import AlignSettings, EvaluationSettings, ExportSettings, PipelineSettings, TrajoptSettings
from toolimit.pipeline.settings import QUICK, WORLD_PRESETS, get_value, with_values
from toolimit.tools import tool_record, tool_records

#: A command's smallest valid argument list, its flags and the settings it starts from.
COMMANDS = {
    "align": (["align", "--tool", "spade", "--demo", "d.npz", "--out", "o"], ALIGN_FLAGS, AlignSettings()),
    "trajopt": (
        ["trajopt", "--robot", "panda", "--tool", "spade", "--alignment", "a", "--out", "o"],
        TRAJOPT_FLAGS,
        TrajoptSettings(),
    ),
    "evaluate": (["evaluate", "--policy", "p"], EVALUATION_FLAGS, EvaluationSettings()),
    "export": (["export", "--trajectory", "t", "--robot", "panda", "--out", "o"], EXPORT_FLAGS, ExportSettings()),
}


def parse(argv: list[str]):
    return build_parser().parse_args(argv)


@pytest.mark.parametrize("command", COMMANDS)
def test_a_stage_command_without_flags_gives_its_settings_defaults(command: str) -> None:
    argv, flags, settings = COMMANDS[command]
    args = parse(argv)
    assert all(getattr(args, flag.path) is None for flag in flags)  # the settings decide, not argparse
    assert apply_flags(settings, flags, args) == settings


@pytest.mark.parametrize("world", WORLD_PRESETS)
def test_run_and_learn_without_flags_give_the_worlds_preset(world: str) -> None:
    argv = ["run", "--tool", "spade", "--robot", "panda", "--demo", "d.npz", "--out", "o", "--world", world]
    expected = PipelineSettings.for_world(world).with_seed(0)
    assert pipeline_settings(parse(argv)) == expected
    assert pipeline_settings(parse([*argv, "--quick"])) == PipelineSettings.for_world(world, quick=True).with_seed(0)
    learn = parse(["learn", "--env", "toolimit/SpadePlanar-v0", "--out", "o"])
    assert learning_config(learn, world) == expected.learning
    assert learning_config(learn) == LearningConfig()


def test_a_tools_own_values_come_over_the_worlds_and_under_quick_and_flags() -> None:
    own = dict(tool_record("scythe").settings["3d"])
    assert own["learning.timesteps"] != WORLD_PRESETS["3d"]["learning.timesteps"]  # else nothing to test
    argv = ["run", "--tool", "scythe", "--robot", "panda", "--demo", "d.npz", "--out", "o"]
    settings = pipeline_settings(parse(argv))
    assert settings == with_values(PipelineSettings.for_world("3d"), own).with_seed(0)
    assert pipeline_settings(parse([*argv, "--quick"])).learning.timesteps == QUICK["learning.timesteps"]
    assert pipeline_settings(parse([*argv, "--timesteps", "1234"])).learning.timesteps == 1234
    learn = parse(["learn", "--task", "task.npz", "--out", "o"])
    assert learning_config(learn, "3d", "scythe") == settings.learning
    assert learning_config(learn, "3d", "spade") == PipelineSettings.for_world("3d").learning
    helps = build_parser()._subparsers._group_actions[0].choices  # type: ignore[union-attr]
    shown = f"(default: 300000 planar, 1500000 3d, {own['learning.timesteps']} 3d scythe)"
    assert shown in " ".join(helps["learn"].format_help().split())


def test_every_tools_own_values_name_settings_fields() -> None:
    for record in tool_records():
        for world, values in record.settings.items():
            settings = PipelineSettings.for_world(world, tool=record.name)  # an unknown field raises here
            assert all(get_value(settings, path) == value for path, value in values.items())


def test_trajopt_and_run_agree() -> None:
    trajopt = apply_flags(TrajoptSettings(), TRAJOPT_FLAGS, parse(COMMANDS["trajopt"][0]))
    for world in WORLD_PRESETS:
        run = ["run", "--tool", "spade", "--robot", "panda", "--demo", "d.npz", "--out", "o", "--world", world]
        assert pipeline_settings(parse(run)).trajopt == trajopt


def test_given_flags_win_over_quick_and_reach_the_right_field() -> None:
    argv = ["run", "--tool", "spade", "--robot", "planar3", "--world", "planar", "--demo", "d.npz", "--out", "o"]
    settings = pipeline_settings(parse([*argv, "--quick", "--samples", "77", "--velocity-weight", "0.5", "--seed", "3",
                                        "--no-clone", "--time-scale", "1,2", "--episodes", "9"]))
    assert settings.align.search.samples == 77 and settings.align.search.candidates == 3  # quick's
    assert settings.trajopt.weights.velocity == 0.5 and settings.trajopt.time_scales == (1.0, 2.0)
    assert settings.learning.clone is False and settings.learning.timesteps == 2000  # quick's
    assert settings.evaluation.episodes == 9 and settings.evaluation.seed == 1003
    assert {settings.align.seed, settings.trajopt.seed, settings.learning.seed} == {3}


@pytest.mark.parametrize(
    ("flags", "settings"),
    [(ALIGN_FLAGS, AlignSettings()), (TRAJOPT_FLAGS, TrajoptSettings()), (LEARNING_FLAGS, LearningConfig()),
     (EVALUATION_FLAGS, EvaluationSettings()), (EXPORT_FLAGS, ExportSettings()),
     (RUN_FLAGS, PipelineSettings())],
)
def test_every_flag_names_a_documented_field(flags: tuple[Flag, ...], settings: object) -> None:
    for flag in flags:
        get_value(settings, flag.path)  # the field exists
        owner = settings
        for name in flag.path.split(".")[:-1]:
            owner = getattr(owner, name)
        assert dataclasses.is_dataclass(owner)
        assert field_help(type(owner), flag.field), f"{flag.path}: no entry in {type(owner).__name__}'s Attributes"


def test_the_help_shows_the_settings_default() -> None:
    helps = build_parser()._subparsers._group_actions[0].choices  # type: ignore[union-attr]
    text = " ".join(helps["run"].format_help().split())
    assert "(default: 5 planar, 40 3d)" in text  # the scythe's value is the 3D world's: not repeated
    assert "(default: 300000 planar, 1500000 3d, " in text  # then the scythe's own
    assert "(default: 0.0001)" in " ".join(helps["trajopt"].format_help().split())


def test_a_refused_value_names_the_flag(capsys: pytest.CaptureFixture[str]) -> None:
    from toolimit.cli import main

    assert main(["trajopt", "--robot", "panda", "--tool", "spade", "--poses", "p.npz", "--out", "o", "--starts", "0"]) == 2
    assert "--starts: must be an integer >= 1, got 0" in capsys.readouterr().err
    assert main(["align", "--tool", "spade", "--demo", "d.npz", "--out", "o", "--candidates", "0"]) == 2
    assert "--candidates: expected a positive integer, got 0" in capsys.readouterr().err


def test_field_help_reads_google_style_attributes() -> None:
    assert field_help(LearningConfig, "value_steps").startswith("Adam steps of the value network's warm-up")
    assert "rad/s" in field_help(LearningConfig, "action_std")
    assert field_help(LearningConfig, "no_such_field") == ""
