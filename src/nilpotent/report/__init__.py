"""The paper reproduced: audit of its statements, figures, data and an offline web page.

* :func:`reproduce` (:mod:`~nilpotent.report.pipeline`) — the whole pipeline,
  written to a folder (``nilpotent reproduce``);
* :func:`run_audit` (:mod:`~nilpotent.report.audit`) — every checkable statement
  of the paper against a computation (``audit.json``, schema ``nilpotent/audit@1``);
* :func:`read_paper` (:mod:`~nilpotent.report.paper`) — the paper's formulas,
  parsed from its LaTeX source shipped in ``report/assets/paper.tex``.
"""

from nilpotent.report.audit import AUDIT_SCHEMA as AUDIT_SCHEMA
from nilpotent.report.audit import Audit as Audit
from nilpotent.report.audit import AuditEntry as AuditEntry
from nilpotent.report.audit import run_audit as run_audit
from nilpotent.report.paper import PaperContent as PaperContent
from nilpotent.report.paper import read_paper as read_paper
from nilpotent.report.pipeline import DEFAULT_OUT as DEFAULT_OUT
from nilpotent.report.pipeline import Reproduction as Reproduction
from nilpotent.report.pipeline import reproduce as reproduce

__all__ = [
    "AUDIT_SCHEMA",
    "DEFAULT_OUT",
    "Audit",
    "AuditEntry",
    "PaperContent",
    "Reproduction",
    "read_paper",
    "reproduce",
    "run_audit",
]
