r"""The audit of the paper: every checkable printed statement against a computation.

:func:`run_audit` reads the paper's formulas from its LaTeX source
(:func:`nilpotent.report.paper.read_paper`), computes the same objects with the
library — the built-in models ``trident-snake`` (body-velocity inputs, the
paper's Section 4, ``r = l = 1``) and ``trident-snake-paper`` (its eq. ``vf``),
:func:`~nilpotent.core.analysis.filtration.analyze`,
:func:`~nilpotent.core.coordinates.approximation.approximate`, brackets with
:func:`~nilpotent.core.lie.brackets.bracket`, and one-period simulations of the
periodic inputs (:mod:`nilpotent.simulation`) — and compares them **when it
runs**.  Nothing in this module states a verdict in advance.

Comparisons are exact where the objects are exact: two expressions are equal
when their difference vanishes at several random rational points evaluated with
30 significant digits (a nonzero value there proves a difference) *and* sympy
cannot show it is nonzero; bracket values at the origin are exact algebraic
numbers compared structurally.  Simulations decide only what is numerical by
nature (which bracket a periodic input realises), with stated tolerances.

Conventions: $[X, Y] = DY\cdot X - DX\cdot Y$; the input
$u_i = -A\omega\sin\omega t$, $u_j = A\omega\cos\omega t$ moves the state by
$\pi A^2 [X_i, X_j](p) + O(A^3)$ per period.

Each :class:`AuditEntry` has the fields of the ``nilpotent/audit@1`` schema
(the interface page): ``id, section, statement, paper, computed, verdict
(agrees|differs), explanation``.

The package follows the paper: :mod:`.entries` (the result types),
:mod:`.compare` (exact comparison, printing, the rank), :mod:`.computed` (the
library's side, built lazily), :mod:`.section4` … :mod:`.section7` (the checks
of each section) and :mod:`.run` (their order and :func:`run_audit`).
"""

from nilpotent.report.audit.compare import format_field as format_field
from nilpotent.report.audit.entries import AGREES as AGREES
from nilpotent.report.audit.entries import AUDIT_SCHEMA as AUDIT_SCHEMA
from nilpotent.report.audit.entries import DIFFERS as DIFFERS
from nilpotent.report.audit.entries import Audit as Audit
from nilpotent.report.audit.entries import AuditEntry as AuditEntry
from nilpotent.report.audit.run import CHECKS as CHECKS
from nilpotent.report.audit.run import run_audit as run_audit

__all__ = [
    "AGREES",
    "AUDIT_SCHEMA",
    "CHECKS",
    "DIFFERS",
    "Audit",
    "AuditEntry",
    "format_field",
    "run_audit",
]
