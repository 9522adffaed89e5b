"""``python -m pinrate.cli``."""

import sys

from .commands import main

sys.exit(main())
