"""``python -m robotool.eval``."""

import sys

from robotool.eval.eval_cli import main

if __name__ == "__main__":  # not when a pool process imports this module
    sys.exit(main())
