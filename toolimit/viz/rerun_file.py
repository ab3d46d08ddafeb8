"""A rerun recording written to an ``.rrd`` file atomically (the file appears only when complete)."""

from __future__ import annotations

import contextlib
import os
from collections.abc import Callable, Iterator
from pathlib import Path

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


def save_recording(
    path: str | os.PathLike[str],
    log: Callable[[rr.RecordingStream], object],
    application_id: str | None = None,
    show_inline: bool = False,
) -> Path | None:
    """Write ``log(recording)`` to ``path`` (.rrd) and return it (None when rerun is disabled); with
    ``show_inline``, log it once more to rerun's viewer inside a notebook (``rerun-sdk[notebook]``).

    The application id defaults to ``toolimit_<file stem>``.
    """
    application_id = application_id or f"toolimit_{Path(path).stem}"
    with recording_file(path, application_id) as recording:
        if recording is None:
            return None
        log(recording)
    if show_inline:
        inline = rr.RecordingStream(application_id)
        inline.notebook_show()
        log(inline)
    return Path(path)
