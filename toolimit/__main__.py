"""``python -m toolimit``: the ``toolimit`` command (:mod:`toolimit.cli`)."""

import sys

from toolimit.cli import main

if __name__ == "__main__":
    sys.exit(main())
