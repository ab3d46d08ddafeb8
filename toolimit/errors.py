"""The package's errors: one base, :class:`ToolimitError`, and its named kinds.

A ``ToolimitError`` says the *input* cannot be used (a malformed file, an unknown name, an
impossible scene, a base no robot may stand on, a path no timing can fix, a QP OSQP cannot
solve): the command line answers it with one line and exit code 2. Anything else raised inside
the package (a plain ``ValueError`` about an array's shape, a ``RuntimeError``) is a bug, and
shows its traceback. Each kind also derives from the built-in error it replaces (``ValueError``,
``RuntimeError``), so ``except ValueError`` around a call keeps working.
"""

from __future__ import annotations


class ToolimitError(Exception):
    """The base of every error that names a problem with the input, not with the package."""


class InputError(ToolimitError, ValueError):
    """Bad user input: an unknown name, an argument out of range, a missing field or a malformed file
    (the message names the file, field, shape or value)."""


class DemoError(InputError):
    """A demonstration is malformed: the message names the field, the shape or the value."""


class TrackError(DemoError):
    """Endpoint tracks or a camera that cannot become a demonstration: a malformed track or camera
    file, too few visible frames, a camera that sees no ground, a mirror ambiguity without a hint."""


class InvalidSetting(InputError):
    """A setting no run can use; ``field`` names the settings field, ``problem`` says what is wrong
    (the command line names the field's flag instead)."""

    def __init__(self, field: str, problem: str) -> None:
        super().__init__(field, problem)
        self.field = field
        self.problem = problem

    def __str__(self) -> str:
        return f"{self.field}: {self.problem}"


class InvalidLearningConfig(InvalidSetting):
    """A learning setting (:class:`toolimit.learn.training.LearningConfig`) no run can use."""


class StageFoundNothing(ToolimitError):
    """A pipeline stage ended without a result to hand on: no alignment candidate within the
    sample budget, or no candidate whose robot replay earns a reward. Not bad input: the command
    line exits with code 1 (more samples or another seed may find one)."""


class InvalidSceneParameters(InputError):
    """Parameters that make a scene impossible (overlap, out of bounds); the message says why."""


class BaseInsideFootprint(ToolimitError, ValueError):
    """The robot's base stands inside a scene element (every solution found, or the one given)."""


class PathOutsideLimits(ToolimitError, ValueError):
    """A limit violation no timing can fix: a sample of the path lies outside a position limit."""


class SolverFailure(ToolimitError, RuntimeError):
    """A solver gave up on a problem (OSQP did not solve a tracking QP); the message gives its status."""


class NoScriptedMotion(InputError):
    """A scene has no hand-made solving motion (the LfD baseline's kinesthetic demonstration)."""


class NoKinestheticDemonstration(ToolimitError, ValueError):
    """The robot tracking a scene's hand-made motion earns nothing at any pace tried: there is no
    kinesthetic demonstration of the task to learn from (the LfD baseline)."""
