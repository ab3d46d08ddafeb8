"""Stage (i): tool demonstrations (types, loaders, cleaning, synthetic generator)."""

from toolimit.demos.cleaning import CleaningReport, clean_demo
from toolimit.demos.motion_estimator import MotionEstimate, canonical_demo, read_motion_estimate
from toolimit.demos.npz_format import load_demo, load_video_trajectory, save_demo
from toolimit.demos.synthetic import SyntheticMotion, synthesize_demo, synthesize_motion
from toolimit.demos.tool_demo import ToolDemo
from toolimit.errors import DemoError

__all__ = [
    "CleaningReport",
    "DemoError",
    "MotionEstimate",
    "SyntheticMotion",
    "ToolDemo",
    "canonical_demo",
    "clean_demo",
    "load_demo",
    "load_video_trajectory",
    "read_motion_estimate",
    "save_demo",
    "synthesize_demo",
    "synthesize_motion",
]
