"""Control experiment (outside the library): plain domain randomisation over the paper's whole
rectangle. The ADR bounds start at the rectangle (aligned +- HALF_RANGE) instead of the aligned box,
and a pull becomes a hold, so the bounds never move (a push at the rectangle's edge is already a
hold). The boundary tests still run every --adr-every updates (the same extra simulation as an ADR
run) and record the success at the rectangle's edges. Usage: python experiment.py <toolimit CLI args...> (the README command, here with --seed 0)"""
import sys

from toolimit.learn import adr, adr_callback


def _full(cls, aligned, axes):
    bounds = _library_at.__func__(cls, aligned, axes)
    for axis in bounds.axes:
        bounds.low[axis], bounds.high[axis] = bounds.limits[0, axis], bounds.limits[1, axis]
    return bounds


_library_at = adr.AdrBounds.at
adr.AdrBounds.at = classmethod(_full)
_library_test = adr.boundary_test


def boundary_test(state, episodes_at, placeable=lambda _: True):
    record = _library_test(state, episodes_at, placeable)
    if record["decision"] == "pull":
        axis, side = "xy".index(record["axis"]), ("low", "high").index(record["side"])
        (state.bounds.low, state.bounds.high)[side][axis] = record["bound"]
        record.update(decision="hold", after=record["bound"], uniform_refused_pull=True)
    return record


adr_callback.boundary_test = boundary_test

from toolimit.cli import main  # noqa: E402

sys.exit(main(sys.argv[1:]))
