"""The audit's result types: one checked statement (:class:`AuditEntry`) and the audit.

The fields are those of the ``nilpotent/audit@1`` schema (the interface page):
``id, section, statement, paper, computed, verdict (agrees|differs), explanation``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from nilpotent.strict_json import json_object

__all__ = ["AGREES", "AUDIT_SCHEMA", "DIFFERS", "Audit", "AuditEntry", "make_entry"]


#: The schema name written into ``audit.json``.
AUDIT_SCHEMA = "nilpotent/audit@1"
AGREES = "agrees"
DIFFERS = "differs"


@dataclass(frozen=True)
class AuditEntry:
    """One checked statement of the paper (the ``nilpotent/audit@1`` entry)."""

    id: str
    section: str
    statement: str
    paper: str
    computed: str
    verdict: str
    explanation: str

    def __post_init__(self) -> None:
        if self.verdict not in (AGREES, DIFFERS):
            raise ValueError(f"verdict must be {AGREES!r} or {DIFFERS!r}, got {self.verdict!r}")

    def as_dict(self) -> dict[str, str]:
        return {
            "id": self.id,
            "section": self.section,
            "statement": self.statement,
            "paper": self.paper,
            "computed": self.computed,
            "verdict": self.verdict,
            "explanation": self.explanation,
        }


@dataclass(frozen=True)
class Audit:
    """The audit of the paper: its entries and the source they were read from.

    Attributes
    ----------
    entries:
        One :class:`AuditEntry` per checked statement, in the paper's order.
    paper_sha256:
        SHA-256 of the LaTeX source the paper's values were read from.
    """

    entries: tuple[AuditEntry, ...]
    paper_sha256: str

    @property
    def agreeing(self) -> tuple[AuditEntry, ...]:
        return tuple(e for e in self.entries if e.verdict == AGREES)

    @property
    def differing(self) -> tuple[AuditEntry, ...]:
        return tuple(e for e in self.entries if e.verdict == DIFFERS)

    def entry(self, entry_id: str) -> AuditEntry:
        """The entry with this id (``KeyError`` if none)."""
        for e in self.entries:
            if e.id == entry_id:
                return e
        raise KeyError(entry_id)

    def to_json(self) -> dict[str, Any]:
        """The ``nilpotent/audit@1`` object of the interface page (plus a summary)."""
        return json_object({
            "schema": AUDIT_SCHEMA,
            "paper_sha256": self.paper_sha256,
            "summary": {
                "entries": len(self.entries),
                "agrees": len(self.agreeing),
                "differs": len(self.differing),
            },
            "entries": [e.as_dict() for e in self.entries],
        })


def make_entry(
    id_: str, section: str, statement: str, paper: str, computed: str, ok: bool, why: str
) -> AuditEntry:
    return AuditEntry(id_, section, statement, paper, computed, AGREES if ok else DIFFERS, why)
