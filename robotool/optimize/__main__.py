"""``python -m robotool.optimize``."""

import sys

from robotool.optimize.optimize_cli import main

sys.exit(main())
