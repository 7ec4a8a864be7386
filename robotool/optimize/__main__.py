"""``python -m robotool.optimize``."""

import sys

from robotool.cli.optimize_command import main

if __name__ == "__main__":  # not when a pool process imports this module
    sys.exit(main())
