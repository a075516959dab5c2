"""Time and memory budgets of planning: one deadline seen by every numeric step.

``plan_global`` (and ``execute_plan``, and ``plan`` when given a ``time_limit``)
opens a :func:`time_budget`; everything below it — the nilpotent steerings, the
candidate integrations of the true system (:mod:`nilpotent.planning.simulation`
bounds their step counts by the time left), the refinement, OMPL, the checks of
the motions — asks :func:`check` between steps, and a step that would pass the
deadline raises :class:`~nilpotent.errors.ComputationLimitError` naming the limit
(exit 2 on the command line, kind ``computation-limit``).

Two deadlines: the **search** stops at :data:`SEARCH_FRACTION` of the limit, so
that a plan found by then can still be re-simulated and verified before the
**hard** deadline, :data:`HARD_FRACTION` of the limit (the ±10 % promise).

The command line counts a limit from the start of the process
(:func:`process_age`: the seconds of start-up are part of what the user waits for).

Memory: :func:`check_memory` refuses (``ComputationLimitError``) an array
estimated above :data:`MEMORY_BUDGET` bytes *before* it is allocated.
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass

from nilpotent.errors import ComputationLimitError

__all__ = [
    "HARD_FRACTION", "MEMORY_BUDGET", "SEARCH_FRACTION", "Budget", "check", "check_memory",
    "current", "process_age", "seconds_left", "time_budget",
]

#: The search (steering, candidates, OMPL) stops at this fraction of the time limit ...
SEARCH_FRACTION = 0.9
#: ... and the verification of a plan found by then at this one.
HARD_FRACTION = 1.05
#: Largest single array (bytes) planning allocates (samples of motions, checks of chords).
MEMORY_BUDGET = 1 << 30


@dataclass(frozen=True)
class Budget:
    """A time limit and when it started (``time.perf_counter`` seconds).

    Attributes
    ----------
    limit : float
        The limit asked for (seconds).
    start : float
        When it started.
    option : str
        The option that set it (named in the error).
    """

    limit: float
    start: float
    option: str = "--time-limit"

    @property
    def deadline(self) -> float:
        """End of the search."""
        return self.start + SEARCH_FRACTION * self.limit

    @property
    def hard(self) -> float:
        """End of the verification of a plan found in time."""
        return self.start + HARD_FRACTION * self.limit

    def left(self, hard: bool = False) -> float:
        """Seconds left before the search (or the hard) deadline (may be negative)."""
        return (self.hard if hard else self.deadline) - time.perf_counter()

    def error(self, what: str) -> ComputationLimitError:
        """The error of a step that ran out of time: names the limit and the step."""
        spent = time.perf_counter() - self.start
        return ComputationLimitError(
            f"time limit reached: {self.option} {self.limit:g} s ({spent:.3g} s spent; "
            f"stopped while {what}); raise {self.option}"
        )


_CURRENT: ContextVar[Budget | None] = ContextVar("nilpotent_planning_budget", default=None)


def current() -> Budget | None:
    """The innermost budget in force (``None``: no limit)."""
    return _CURRENT.get()


def process_age() -> float:
    """Seconds since this process started (0 where the system does not say: not Linux)."""
    try:
        with open("/proc/self/stat", encoding="ascii") as f:
            stat = f.read()
        with open("/proc/uptime", encoding="ascii") as f:
            uptime = float(f.read().split()[0])
        # the fields after the command name (which may hold spaces) in parentheses
        start_ticks = float(stat.rsplit(")", 1)[1].split()[19])
        age = uptime - start_ticks / os.sysconf("SC_CLK_TCK")
    except (OSError, ValueError, IndexError):
        return 0.0
    return age if 0.0 <= age < 3600.0 else 0.0


@contextmanager
def time_budget(
    seconds: float, option: str = "--time-limit", already: float = 0.0
) -> Iterator[Budget | None]:
    """Run the block under a time limit of ``seconds`` from ``already`` seconds ago.

    Nested budgets never extend an outer one: the innermost ends no later than
    the enclosing one.  Yields the budget in force (``None``: no limit).

    Parameters
    ----------
    seconds : float
        The limit (``> 0``; ``inf``: none beyond the enclosing one).
    option : str
        The option named in the errors.
    already : float
        Seconds already spent (counted in the limit; e.g. :func:`process_age`).

    Raises
    ------
    ValueError
        ``seconds`` is not a positive number.
    """
    if not seconds > 0:
        raise ValueError(f"a time budget needs a positive number of seconds, got {seconds}")
    now = time.perf_counter()
    outer = _CURRENT.get()
    new = Budget(float(seconds), now - max(0.0, already), option)
    budget: Budget | None = new
    if outer is not None and (math.isinf(seconds) or new.hard > outer.hard):
        budget = outer
    elif math.isinf(seconds):
        budget = None
    token = _CURRENT.set(budget)
    try:
        yield budget
    finally:
        _CURRENT.reset(token)


def seconds_left(hard: bool = False) -> float:
    """Seconds left in the budget in force (``inf`` without one)."""
    b = _CURRENT.get()
    return math.inf if b is None else b.left(hard)


def check(what: str, hard: bool = False) -> None:
    """Raise if the budget in force has run out.

    Parameters
    ----------
    what : str
        The step about to run ("steering piece 3", ...), named in the error.
    hard : bool
        Check against the hard deadline (verification of a found plan).

    Raises
    ------
    ComputationLimitError
        The deadline has passed.
    """
    b = _CURRENT.get()
    if b is not None and b.left(hard) <= 0:
        raise b.error(what)


def check_memory(nbytes: float, what: str, hint: str = "") -> None:
    """Refuse an allocation estimated at ``nbytes`` above :data:`MEMORY_BUDGET`.

    Parameters
    ----------
    nbytes : float
        The estimated size.
    what : str
        What would be allocated.
    hint : str
        What the user can change (e.g. ``"raise --max-piece"``).

    Raises
    ------
    ComputationLimitError
        The estimate exceeds the budget.
    """
    if not nbytes <= MEMORY_BUDGET:
        more = f"; {hint}" if hint else ""
        raise ComputationLimitError(
            f"memory limit: {what} would take about {nbytes / 2**30:.3g} GiB, above the "
            f"planning budget of {MEMORY_BUDGET / 2**30:g} GiB{more}"
        )
