"""``python -m s2r`` runs the CLI."""

import sys

from s2r.cli import main

sys.exit(main())
