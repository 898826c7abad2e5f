"""`python -m rcsc` runs the command-line interface."""

import sys

from rcsc.cli import main

sys.exit(main())
