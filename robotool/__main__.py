"""``python -m robotool`` runs the ``robotool`` command line."""

import sys

from robotool.cli import main

sys.exit(main())
