"""Running the audit: the checks in the order of the paper, and :func:`run_audit`."""

from __future__ import annotations

from collections.abc import Callable, Collection, Iterable

from nilpotent.errors import OptionError
from nilpotent.progress import ProgressCallback, ProgressEvent
from nilpotent.report.audit.computed import Computed
from nilpotent.report.audit.entries import Audit, AuditEntry
from nilpotent.report.audit.section4 import (
    check_growth,
    check_liebrackets,
    check_motion_claims,
    check_section4_fields,
    check_vf,
)
from nilpotent.report.audit.section5 import check_components, check_privileged
from nilpotent.report.audit.section6 import (
    check_approximation,
    check_first_order,
    check_hat_brackets,
    check_homogeneous_form,
    check_labels,
    check_step,
    check_weights,
)
from nilpotent.report.audit.section7 import (
    check_approximation_x,
    check_inputs,
    check_motions_coincide,
)
from nilpotent.report.paper import PaperContent, read_paper

__all__ = ["CHECKS", "Check", "run_audit"]

#: A group of checks: reads the paper and the computed side, yields entries.
Check = Callable[[PaperContent, Computed], Iterable[AuditEntry]]


#: The checks, in the order of the paper.
CHECKS: tuple[tuple[str, Check], ...] = (
    ("growth vector", check_growth),
    ("Section 4 fields", check_section4_fields),
    ("eq. vf", check_vf),
    ("eq. liebrackets", check_liebrackets),
    ("Figs 2-4 motions", check_motion_claims),
    ("Section 5 components", check_components),
    ("privileged coordinates", check_privileged),
    ("weights", check_weights),
    ("nilpotent approximation", check_approximation),
    ("homogeneous form", check_homogeneous_form),
    ("first order", check_first_order),
    ("nilpotency step", check_step),
    ("brackets of the approximation", check_hat_brackets),
    ("bracket names", check_labels),
    ("approximation in x", check_approximation_x),
    ("bracket motions coincide", check_motions_coincide),
    ("periodic inputs", check_inputs),
)


def run_audit(
    paper: PaperContent | None = None,
    *,
    only: Collection[str] | None = None,
    progress: ProgressCallback | None = None,
) -> Audit:
    """Check every statement of the paper by computation.

    Parameters
    ----------
    paper:
        The parsed paper (default: :func:`read_paper` of the shipped source).
    only:
        Run only these groups of checks (names of :data:`CHECKS`); default all.
    progress : ProgressCallback or None
        Called with ``ProgressEvent(group, done, total)`` before each group of checks
        runs (its name, the groups done, their number; :mod:`nilpotent.progress`).

    Returns
    -------
    Audit
        One :class:`AuditEntry` per checked statement, in the paper's order.

    Raises
    ------
    OptionError
        ``only`` names a group of checks that does not exist.
    RuntimeError
        Two checks produced the same entry id (a bug of the audit, not of the input).
    """
    content = read_paper() if paper is None else paper
    known = [name for name, _ in CHECKS]
    unknown = sorted(set(only or ()) - set(known))
    if unknown:
        raise OptionError(f"unknown audit checks {unknown}; known: {', '.join(known)}")
    computed = Computed(content)
    entries: list[AuditEntry] = []
    chosen = [(name, check) for name, check in CHECKS if only is None or name in only]
    for done, (name, check) in enumerate(chosen):
        if progress is not None:
            progress(ProgressEvent(name, done, len(chosen)))
        entries.extend(check(content, computed))
    ids = [e.id for e in entries]
    dup = sorted({i for i in ids if ids.count(i) > 1})
    if dup:
        raise RuntimeError(f"duplicate audit ids: {dup}")
    return Audit(tuple(entries), content.source_sha256)
