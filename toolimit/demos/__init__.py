"""Stage (i): tool demonstrations (types, loaders, cleaning, synthetic generator)."""

from toolimit.demos.tool_demo import DemoError, ToolDemo

__all__ = ["DemoError", "ToolDemo"]
