r"""Integration engines: one registry of classes, one written contract.

Every engine integrates a batch of ``B`` trajectories of

.. math::

    \dot x = \sum_{i=1}^m u_i(t)\, X_i(x), \qquad x(0) = x_0^{(b)},

under ``B`` controls given as data (:class:`~nilpotent.numeric.signals.Signal`:
piecewise sums of sinusoids, time restarting in every segment).  The registry
:data:`ENGINES` maps a name to an instance; :func:`choose_engine` decides what
``engine="auto"`` means; :func:`nilpotent.numeric.integrate.integrate` is the
entry point users call.

==========  ====================  ===========================================================
name        methods               what runs
==========  ====================  ===========================================================
``numba``   adaptive, fixed       DOP853 kernels compiled into the system's cached module
                                  (:mod:`nilpotent.numeric.kernels`), ``prange`` over the batch
``numpy``   fixed                 the same fixed-step DOP853 vectorised over the batch
``scipy``   adaptive              :func:`scipy.integrate.solve_ivp` (DOP853) per trajectory:
                                  the reference; also takes inputs as Python functions
``heyoka``  adaptive              heyoka's Taylor method in SIMD batches (fastest measured)
==========  ====================  ===========================================================

Writing an engine (the contract; scipy's ``OdeSolver`` docstring is the model)
------------------------------------------------------------------------------
Subclass :class:`Engine`, set the class attributes and implement
:meth:`Engine.solve`, then add an instance to :data:`ENGINES`.

Class attributes
    ``name`` (the registry key), ``methods`` (the subset of
    :data:`~nilpotent.numeric.integrate.METHODS` it runs: ``"adaptive"``
    and/or ``"fixed"``), ``summary`` (one line for docs and messages).

``available()``
    Whether its dependencies import; an engine that is asked for but not
    available raises :class:`~nilpotent.errors.MissingExtraError` naming the install.

``handles(system)``
    Whether it can express the system's fields at all (default ``True``; heyoka
    has no ``Abs``): ``"auto"`` never picks an engine that cannot.

``solve(system, xs, signal, times, *, adaptive, steps, rtol, atol, max_steps,
min_step, bound, threads)``
    Inputs, all already validated by ``integrate``: ``system`` a
    :class:`~nilpotent.numeric.compile.CompiledSystem` with ``n`` coordinates
    and ``m`` fields; ``xs`` ``(B, n)`` C-contiguous float64 start states;
    ``signal`` a batch of exactly ``B`` controls with ``m`` inputs;
    ``times`` ``(T,)`` sorted global sample times within every control's
    duration; ``adaptive`` selects the method (``steps`` per segment for the
    fixed one); ``rtol``, ``atol``, ``max_steps`` (accepted + rejected),
    ``min_step`` and ``bound`` as in ``integrate``; ``threads`` a hint
    (``None``: the engine's default).

    Returns ``(final, samples, info)``: ``final`` ``(B, n)`` the state at the
    end of each control (the last state reached if stopped early);
    ``samples`` ``(B, T, n)`` the states at ``times``, NaN past an early stop;
    ``info`` ``(B, 4)`` float: :class:`Status` code, accepted steps, rejected
    steps, and an error estimate (NaN where the engine has none).

    Obligations: integrate every segment from its start, restarting the step
    control at segment boundaries (the inputs may jump there); stop a
    trajectory, never raise, when some ``|x_k| > bound``
    (:attr:`Status.BLOW_UP`), when the state is not finite
    (:attr:`Status.NON_FINITE`), after ``max_steps`` (:attr:`Status.MAX_STEPS`)
    or below ``min_step`` (:attr:`Status.STEP_TOO_SMALL`); meet the accuracy
    the method promises (``adaptive``: every accepted step has local error
    ≤ ``atol + rtol·|x|``); leave its inputs unchanged.  Raise only for a
    missing dependency or inputs outside what the engine can do
    (:class:`~nilpotent.errors.OptionError`, saying what to use instead).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from nilpotent.errors import OptionError
from nilpotent.numeric.engines.base import Engine as Engine
from nilpotent.numeric.engines.base import EngineOutput as EngineOutput
from nilpotent.numeric.engines.base import Status as Status
from nilpotent.numeric.engines.base import check_times as check_times
from nilpotent.numeric.engines.base import state_status as state_status

__all__ = [
    "AUTO_NUMBA_BATCH", "ENGINES", "HEYOKA_MIN_CYCLES", "Engine", "EngineOutput", "Status",
    "check_times", "choose_engine", "engine_names", "input_cycles", "state_status",
]

#: ``engine="auto"`` compiles numba kernels from this batch size on (below it
#: only when they are already cached) and prefers heyoka from it on.
AUTO_NUMBA_BATCH = 64

#: ``engine="auto"`` (adaptive method) prefers heyoka for a smaller batch when its longest
#: control runs through at least this many periods of its fastest harmonic: measured
#: on 2 cores for one bracket motion of the unicycle (renamed, caches cold), heyoka
#: costs 0.5 s of CPU (its compilation included; 0.3 s with its disk cache) where
#: ``solve_ivp`` costs 0.7 s for one period and 30 s for 1,000 periods.
HEYOKA_MIN_CYCLES = 0.5


def _registry() -> dict[str, Engine]:
    from nilpotent.numeric.engines.heyoka_engine import HeyokaEngine
    from nilpotent.numeric.engines.numba_engine import NumbaEngine
    from nilpotent.numeric.engines.numpy_engine import NumpyEngine
    from nilpotent.numeric.engines.scipy_engine import ScipyEngine

    return {e.name: e for e in (NumbaEngine(), NumpyEngine(), ScipyEngine(), HeyokaEngine())}


#: The engines by name (``"auto"`` is not one: :func:`choose_engine` resolves it).
ENGINES: dict[str, Engine] = _registry()


def engine_names() -> tuple[str, ...]:
    """``("auto", *ENGINES)``: every value ``engine=`` accepts."""
    return ("auto", *ENGINES)


def input_cycles(signal: Any) -> float:
    """How many periods of its fastest harmonic the longest control of ``signal`` runs through.

    ``max_b Σ_s K·|ω_{b,s}|·d_{b,s} / (2π)`` over the segments ``s`` (``K`` the
    number of harmonics; 0 for constant inputs).
    """
    if signal.harmonics == 0 or signal.durations.size == 0:
        return 0.0
    span = np.sum(np.abs(signal.omegas) * signal.durations, axis=1)
    return float(signal.harmonics * np.max(span) / (2 * np.pi))


def choose_engine(
    system: Any, method: str, engine: str, batch: int, cycles: float | None = None
) -> Engine:
    """The engine that ``engine`` (a name or ``"auto"``) means for ``method`` and ``batch``.

    ``"auto"``: for the adaptive method, ``heyoka`` when heyoka is installed,
    can express the fields (:meth:`Engine.handles`: not ``Abs``, for one) and
    the batch has at least :data:`AUTO_NUMBA_BATCH` trajectories or ``cycles``
    (how many periods of its fastest harmonic the longest control runs through;
    ``None``: not known) is at least :data:`HEYOKA_MIN_CYCLES`; otherwise
    ``numba`` when its kernels for ``system`` are already in the on-disk cache
    or the batch is that large, else ``scipy`` (adaptive) / ``numpy`` (fixed).

    Parameters
    ----------
    system : CompiledSystem
        The system to integrate.
    method : str
        ``"adaptive"`` or ``"fixed"``.
    engine : str
        An engine name or ``"auto"``.
    batch : int
        How many trajectories.
    cycles : float or None
        The inputs' length in periods (:func:`input_cycles`), or ``None``.

    Raises
    ------
    OptionError
        An unknown name, or an engine that does not run ``method``.
    """
    if engine == "auto":
        numba = ENGINES["numba"]
        long_inputs = cycles is not None and cycles >= HEYOKA_MIN_CYCLES
        heyoka = ENGINES["heyoka"]
        if (method == "adaptive" and (batch >= AUTO_NUMBA_BATCH or long_inputs)
                and heyoka.available() and heyoka.handles(system)):
            return heyoka
        if numba.available() and (batch >= AUTO_NUMBA_BATCH or numba.cached(system)):
            return numba
        return ENGINES["scipy" if method == "adaptive" else "numpy"]
    if engine not in ENGINES:
        raise OptionError(f"unknown engine {engine!r} (choose from {', '.join(engine_names())})")
    chosen = ENGINES[engine]
    if method not in chosen.methods:
        runs = ", ".join(e.name for e in ENGINES.values() if method in e.methods)
        raise OptionError(f"method {method!r} runs on the engines {runs}, not {engine!r}")
    return chosen
