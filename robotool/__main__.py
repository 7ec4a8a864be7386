"""``python -m robotool`` runs the ``robotool`` command line."""

import sys

from robotool.cli import main

if __name__ == "__main__":  # not when a pool process imports this module
    sys.exit(main())
