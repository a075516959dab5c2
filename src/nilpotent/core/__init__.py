"""Symbolic, exact core of `nilpotent` (no numpy arrays, no matplotlib, no scipy).

Five rooms, in the order the mathematics runs; each imports only the rooms
before it (``tests/test_architecture.py``), and each ``__init__`` is its short
public face:

1. :mod:`nilpotent.core.model` — what a user writes: the expression grammar,
   :class:`~nilpotent.core.model.system.ControlSystem`, points, limits and
   outlines, model files;
2. :mod:`nilpotent.core.decide` — the one zero and rank engine: exact and
   certified values of constants, certified spans;
3. :mod:`nilpotent.core.lie` — bracket words, Hall basis, brackets, fields as
   polynomials in atoms and the values of words at a point;
4. :mod:`nilpotent.core.analysis` — generic growth, orbits, the singular locus
   and the filtration at a point (:func:`~nilpotent.core.analysis.filtration.analyze`);
5. :mod:`nilpotent.core.coordinates` — weighted jets, non-holonomic orders,
   exponential maps, privileged coordinates and the nilpotent approximation
   with its certificate.
"""
