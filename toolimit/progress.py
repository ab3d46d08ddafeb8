"""Progress bars: tqdm's notebook widget where ipywidgets is installed, its text bar elsewhere.

``tqdm.auto`` picks the widget in any notebook and, without ipywidgets, warns "IProgress not found"
at the top of the notebook; the text bar works everywhere.
"""

from __future__ import annotations

import importlib.util

if importlib.util.find_spec("ipywidgets") is not None:
    from tqdm.auto import tqdm
else:
    from tqdm.std import tqdm

__all__ = ["tqdm"]
