"""The package version (also in ``pyproject.toml``), importable from any layer.

Modules that record the version in their results (sweeps) import it from here,
not from the top-level package, so no import points upward.
"""

__version__ = "0.1.0"
