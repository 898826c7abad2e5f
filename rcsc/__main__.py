"""`python -m rcsc` runs the command-line interface (`rcsc.launch`)."""

from rcsc.launch import entry

entry()
