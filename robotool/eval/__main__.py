"""``python -m robotool.eval``."""

import sys

from robotool.eval.eval_cli import main

sys.exit(main())
