"""``python -m mlplc2.cli``: the ``mlplc2`` command line (:func:`mlplc2.cli.main`)."""

import sys

from . import main

sys.exit(main())
