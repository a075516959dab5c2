"""The budget on the Hall words that :func:`~nilpotent.core.analysis.analyze` examines at p.

At a singular point the span of the brackets can stall for some lengths and
grow later, so the search at the point goes through every Hall word of each
length; their number grows like $m^k/k$ (Witt's formula), and this budget bounds it.
"""

from __future__ import annotations

from nilpotent.errors import ComputationLimitError


def budget_length(m: int) -> int:
    """The longest length whose Hall words (all lengths up to it) fit :data:`HALL_WORD_BUDGET`."""
    total, length = 0, 0
    while True:
        count = _witt(m, length + 1)
        if total + count > HALL_WORD_BUDGET and length >= 2:
            return length
        total += count
        length += 1


HALL_WORD_BUDGET = 5000
"""Most Hall words the default ``max_length`` lets :func:`analyze` examine at ``p``."""


def default_max_length(n: int, m: int) -> int:
    r"""The default longest bracket length examined at a point.

    $\max(2n + 2, 12)$, lowered so that at most :data:`HALL_WORD_BUDGET` Hall
    words (Witt's formula) of length $\le$ it exist for $m$ generators; it only
    matters at singular points, where the span can stall and grow again later.
    """
    total = 0
    length = 0
    wanted = max(2 * n + 2, 12)
    while length < wanted:
        count = _witt(m, length + 1)
        if total + count > HALL_WORD_BUDGET and length >= 2:
            break
        total += count
        length += 1
    return length


def check_hall_budget(m: int, max_length: int) -> None:
    """Refuse an explicit ``max_length`` whose Hall words exceed :data:`HALL_WORD_BUDGET`.

    Raises
    ------
    ComputationLimitError
        Naming the number of Hall words, the budget and the option (``--max-length``).
    """
    total = 0
    for length in range(1, max_length + 1):
        total += _witt(m, length)
        if total > HALL_WORD_BUDGET:
            raise ComputationLimitError(
                f"--max-length {max_length} with {m} fields means more than "
                f"{HALL_WORD_BUDGET:,} Hall words (the budget HALL_WORD_BUDGET; already "
                f"{total:,} up to length {length}); give a --max-length of at most "
                f"{default_max_length_for_budget(m)}"
            )


def default_max_length_for_budget(m: int) -> int:
    """The longest bracket length whose Hall words fit in :data:`HALL_WORD_BUDGET`."""
    total = length = 0
    while True:
        count = _witt(m, length + 1)
        if total + count > HALL_WORD_BUDGET:
            return max(length, 1)
        total += count
        length += 1


def _witt(m: int, k: int) -> int:
    """Dimension of the degree-k part of the free Lie algebra on m generators."""
    return sum(_mobius(d) * m ** (k // d) for d in range(1, k + 1) if k % d == 0) // k


def _mobius(k: int) -> int:
    result, q = 1, 2
    while q * q <= k:
        if k % q == 0:
            k //= q
            if k % q == 0:
                return 0
            result = -result
        q += 1
    return -result if k > 1 else result
