"""``python -m nilpotent`` runs the command line (:func:`nilpotent.entry.run`: the signal
handlers first, then the command)."""

from nilpotent.entry import run

run()
