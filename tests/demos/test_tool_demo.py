"""ToolDemo: value equality and slicing."""

import numpy as np

from toolimit.demos import ToolDemo


def _demo(shift: float = 0.0, source: str = "") -> ToolDemo:
    head = np.column_stack([np.linspace(0, 1, 12) + shift, np.zeros(12), np.zeros(12)])
    return ToolDemo(head=head, handle=head + [0.0, 0.0, 0.4], fps=24, tool="spade", source=source)


def test_demos_compare_by_value_not_by_source():
    assert _demo() == _demo(source="elsewhere")
    assert _demo() != _demo(shift=1e-3)
    assert _demo() != _demo().resampled(30)
    assert _demo() != "spade"


def test_sliced_keeps_the_frames_and_the_rate():
    demo = _demo()
    part = demo.sliced(1, 12)
    assert part.n_frames == 11 and part.fps == demo.fps and part.tool == demo.tool
    assert np.array_equal(part.head, demo.head[1:12]) and np.array_equal(part.handle, demo.handle[1:12])
