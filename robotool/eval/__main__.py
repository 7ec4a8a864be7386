"""``python -m robotool.eval``."""

import sys

from robotool.eval.cli import main

sys.exit(main())
