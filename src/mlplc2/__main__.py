"""``python -m mlplc2``: the ``mlplc2`` command line (:func:`mlplc2.cli.main`)."""

import sys

from .cli import main

if __name__ == "__main__":
    sys.exit(main())
