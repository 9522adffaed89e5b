"""``python -m pinrate.cli``."""

import sys

from .entry import main

sys.exit(main())
