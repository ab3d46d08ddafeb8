"""toolimit: a robot learns to use a tool from one video demonstration.

The package is laid out as the pipeline of Zorina et al. (RA-L 2022):
``demos`` (i) -> ``scenes`` + ``align`` (ii) -> ``robots`` + ``trajopt`` (iii) -> ``learn`` (iv),
on the tool frame and tool registry of ``tools``, chained by ``pipeline`` (each stage a function with typed settings, and ``run_pipeline``), with
``deploy`` for export to a real robot, ``experiments`` for the paper's figure, ``viz`` for meshcat
views and rerun recordings and ``cli`` for the ``toolimit`` command.

``import toolimit`` loads none of them: ``toolimit.demos`` (any name of :data:`SUBPACKAGES`)
imports its subpackage on first access (PEP 562), so that the command line and a user's script
pay only for the stages they use (torch, pinocchio and numba take seconds to load).
"""

import importlib as _importlib  # private names: dir(toolimit) is what a user calls
from types import ModuleType as _ModuleType

__version__ = "0.1.0"

#: The subpackages a user reaches as attributes of ``toolimit``, imported on first access.
SUBPACKAGES = (
    "tools",
    "demos",
    "scenes",
    "align",
    "robots",
    "trajopt",
    "learn",
    "pipeline",
    "deploy",
    "experiments",
    "viz",
)


def __getattr__(name: str) -> _ModuleType:
    """``toolimit.<subpackage>``: imports it once (it is then a plain attribute of the package)."""
    if name in SUBPACKAGES:
        return _importlib.import_module(f"{__name__}.{name}")
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    """The package's own names and the subpackages, loaded or not (for completion and ``dir``)."""
    return sorted(set(globals()) | set(SUBPACKAGES))
