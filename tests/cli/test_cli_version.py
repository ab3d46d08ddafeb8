"""``toolimit --version``: the version written once, in ``toolimit.__version__``."""

from __future__ import annotations

from importlib.metadata import version

import pytest

import toolimit
from toolimit.cli import main


def test_version_is_the_installed_packages(capsys):
    with pytest.raises(SystemExit) as ended:
        main(["--version"])
    assert ended.value.code == 0
    assert capsys.readouterr().out.strip() == f"toolimit {toolimit.__version__}"
    assert version("toolimit") == toolimit.__version__  # pyproject reads it from the package
