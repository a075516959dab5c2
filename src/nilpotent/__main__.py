"""``python -m nilpotent`` runs the command line."""

from nilpotent.cli import run

run()
