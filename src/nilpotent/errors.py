"""Error types of `nilpotent`.

Every error a user can cause is a :class:`NilpotentError`; the CLI turns it into
one clear message and exit status 2 (``{"error": {"kind", "message"}}`` under
``--json``).  ``kind`` is the class's :attr:`NilpotentError.kind`.
"""

from __future__ import annotations


class NilpotentError(Exception):
    """Base class of the errors a user can cause (bad input, impossible requests)."""

    kind: str = "error"


class ExpressionError(NilpotentError):
    """A user-written expression is outside the safe grammar or malformed."""

    kind = "expression"


class ModelError(NilpotentError):
    """A model (built-in name, model file, parameter) is unknown or invalid."""

    kind = "model"


class PointError(NilpotentError):
    """A point given by the user (``--at``, ``--from``, ``--to``) is invalid."""

    kind = "point"


class NotBracketGeneratingError(NilpotentError):
    """The brackets of the fields do not span the tangent space at the point."""

    kind = "not-bracket-generating"


class SingularPointError(NilpotentError):
    """The request needs a regular point and the point is singular."""

    kind = "singular-point"


class NotPrivilegedError(NilpotentError):
    """The requested coordinates are not privileged at the point."""

    kind = "not-privileged"


class OptionError(NilpotentError):
    """A command-line option or API argument has an invalid value."""

    kind = "option"


class MissingExtraError(NilpotentError):
    """An optional dependency (an extra such as ``jax`` or ``dask``) is needed but missing."""

    kind = "missing-extra"


class IntegrationError(NilpotentError):
    """A numerical integration failed (blow-up, step size underflow, too many steps)."""

    kind = "integration"


class PlanningError(NilpotentError):
    """Steering failed: singular start/goal/path, or no progress."""

    kind = "planning"


class ComputationLimitError(NilpotentError):
    """A symbolic result would be too large to compute or print in reasonable time."""

    kind = "computation-limit"


class OutputError(NilpotentError):
    """An output (a file, a folder, stdout) cannot be written: missing or read-only folder,
    a folder where a file is expected, a full disk, a closed stdout."""

    kind = "output"


class UsageError(NilpotentError):
    """The command line itself is malformed: a missing or unknown option, a value of the
    wrong type (reported by the option parser before a command runs)."""

    kind = "usage"


class WorldError(NilpotentError):
    """A world file (workspace bounds and obstacles) is missing or malformed."""

    kind = "world"


class DaskError(NilpotentError):
    """A sweep on Dask could not finish: the scheduler was lost, no chunk finished within
    the progress timeout (no workers, a hung worker), a chunk killed its workers, or a
    worker cannot run the chunks."""

    kind = "dask"
