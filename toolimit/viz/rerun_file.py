"""A rerun recording written to an ``.rrd`` file atomically (the file appears only when complete)."""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterator

import rerun as rr

from toolimit.artifacts import atomic_path


@contextlib.contextmanager
def recording_file(path: str | os.PathLike[str], application_id: str) -> Iterator[rr.RecordingStream | None]:
    """Yield a recording streamed to a temporary file, renamed onto ``path`` when the block ends.

    Yields None when rerun is disabled (``RERUN=off``): the caller then logs nothing and no file
    is written.
    """
    recording = rr.RecordingStream(application_id)
    if not rr.is_enabled(recording):
        yield None
        return
    with atomic_path(path) as tmp:
        recording.save(tmp)
        yield recording
        recording.flush()
        recording.disconnect()
