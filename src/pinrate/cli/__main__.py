"""``python -m pinrate.cli``: the console script's entry point (:mod:`.console`)."""

import sys

from .console import main

sys.exit(main())
