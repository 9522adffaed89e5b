"""``python -m pinrate``: the command line, as the ``pinrate`` console script runs it
(:mod:`pinrate.cli.console`)."""

import sys

from .cli.console import main

sys.exit(main())
