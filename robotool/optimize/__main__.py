"""``python -m robotool.optimize``."""

import sys

from robotool.optimize.optimize_cli import main

if __name__ == "__main__":  # not when a pool process imports this module
    sys.exit(main())
