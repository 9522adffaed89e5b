"""``python -m pinrate.cli``."""

import sys

from .main import main

sys.exit(main())
