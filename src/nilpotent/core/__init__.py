"""Symbolic, exact core of `nilpotent` (no numpy arrays, no matplotlib, no scipy)."""
