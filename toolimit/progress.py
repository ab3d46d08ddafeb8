"""Progress of long work, shown the way its reader sees it.

:func:`progress_bar` takes tqdm's arguments and picks, when the bar is made:

- on a terminal (standard error is a TTY), tqdm's text bar, redrawn in place;
- in a Jupyter notebook with ipywidgets, tqdm's widget;
- anywhere else (a log file, a pipe, CI, a notebook without ipywidgets), :class:`LogLines`: one
  plain line every :data:`LOG_INTERVAL_S` seconds (count, percentage, elapsed time, ETA, the
  bar's postfix such as a success rate) and one at the end, never a carriage-return redraw, so
  that a log holds a readable history and a notebook's stored output stays small.
"""

from __future__ import annotations

import importlib.util
import sys
from typing import Any

from tqdm.std import tqdm

#: Seconds between two lines of a :class:`LogLines` bar.
LOG_INTERVAL_S = 5.0


class LogLines(tqdm):  # type: ignore[type-arg]
    """A tqdm bar that writes one plain line per :data:`LOG_INTERVAL_S` seconds and a last one on
    close (module docstring); a postfix set with ``refresh=False`` shows on the next line."""

    def __init__(self, *args: Any, **kwargs: Any):
        iterable = args[0] if args else kwargs.get("iterable")
        total = kwargs.get("total", len(iterable) if hasattr(iterable, "__len__") else None)  # type: ignore[arg-type]
        counted = "{desc}: {n_fmt}/{total_fmt} {unit} ({percentage:.0f}%), {elapsed} elapsed, ETA {remaining}"
        kwargs["bar_format"] = (counted if total else "{desc}: {n_fmt} {unit}, {elapsed} elapsed") + "{postfix}"
        kwargs.setdefault("mininterval", LOG_INTERVAL_S)
        kwargs["miniters"] = 0  # an update(0) (a postfix change) may write a line when it is due
        kwargs["leave"] = False  # close() writes the last line itself, without tqdm's clearing
        super().__init__(*args, **kwargs)

    def display(self, msg: str | None = None, pos: int | None = None) -> bool:
        """Write the bar's state as one line; tqdm's clearing (an empty message) writes nothing and
        returns False, so that no carriage return follows it."""
        if msg == "":
            return False
        self.fp.write((self.__str__() if msg is None else msg) + "\n")
        self.fp.flush()
        return True

    def close(self) -> None:
        """Write the final line (when the bar was shown at all), then close."""
        if not self.disable and self.n != getattr(self, "last_print_n", self.n):
            self.display()
        super().close()


def _in_notebook() -> bool:
    """Whether this process is a Jupyter kernel (tqdm.autonotebook's test)."""
    ipython = sys.modules.get("IPython")
    shell = ipython.get_ipython() if ipython is not None else None  # type: ignore[attr-defined]
    return shell is not None and "IPKernelApp" in getattr(shell, "config", {})


def progress_bar(*args: Any, **kwargs: Any) -> tqdm:  # type: ignore[type-arg]
    """A progress bar with tqdm's arguments, drawn for where it is read (module docstring)."""
    if _in_notebook() and importlib.util.find_spec("ipywidgets") is not None:
        from tqdm.notebook import tqdm as widget

        return widget(*args, **kwargs)
    if sys.stderr.isatty():
        return tqdm(*args, **kwargs)
    return LogLines(*args, **kwargs)


__all__ = ["LOG_INTERVAL_S", "LogLines", "progress_bar"]
