"""``python -m robotool.optimize``."""

import sys

from robotool.optimize.cli import main

sys.exit(main())
