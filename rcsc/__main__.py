"""`python -m rcsc` runs the command-line interface."""

from rcsc.cli import entry

entry()
