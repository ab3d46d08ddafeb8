"""Progress in a log: plain lines, never carriage-return redraws; a terminal keeps tqdm's bar."""

from __future__ import annotations

import io
import sys

from tqdm.std import tqdm

from toolimit.progress import LOG_INTERVAL_S, LogLines, progress_bar


def test_a_log_gets_plain_lines_with_count_eta_and_postfix():
    log = io.StringIO()
    with progress_bar(total=100, desc="PPO", unit="step", file=log, mininterval=0) as bar:
        assert isinstance(bar, LogLines)
        for _ in range(4):
            bar.set_postfix(success="0.50", refresh=False)
            bar.update(25)
    text = log.getvalue()
    assert "\r" not in text
    lines = text.splitlines()
    assert lines[0].startswith("PPO: 0/100 step (0%)")
    assert lines[-1].startswith("PPO: 100/100 step (100%)") and "ETA" in lines[-1] and "success=0.50" in lines[-1]


def test_lines_come_at_most_every_few_seconds_and_once_at_the_end():
    log = io.StringIO()
    for _ in progress_bar(range(10_000), desc="cloning", file=log):
        pass
    lines = log.getvalue().splitlines()
    assert LOG_INTERVAL_S >= 1 and len(lines) == 2  # the start and the end of a loop shorter than the interval
    assert lines[-1].startswith("cloning: 10000/10000 it (100%)")


def test_a_bar_without_total_counts_only():
    log = io.StringIO()
    bar = progress_bar(desc="samples", unit="sample", file=log, mininterval=0)
    bar.update(3)
    bar.close()
    assert log.getvalue().splitlines()[-1].startswith("samples: 3 sample")


def test_a_disabled_bar_writes_nothing():
    log = io.StringIO()
    with progress_bar(total=5, file=log, disable=True) as bar:
        bar.update(5)
    assert log.getvalue() == ""


def test_a_terminal_gets_tqdm_s_bar(monkeypatch):
    monkeypatch.setattr(sys.stderr, "isatty", lambda: True, raising=False)
    bar = progress_bar(total=3, file=io.StringIO())
    assert type(bar) is tqdm
    bar.close()
