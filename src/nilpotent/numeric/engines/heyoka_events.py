"""The heyoka engine's general path: one SIMD batch of trajectories through its events.

:func:`run_chunk` integrates up to one SIMD batch (``taylor_adaptive_batch``)
of trajectories from 0 through their events in time order: the ends of their
segments (where the next segment's inputs are loaded and the lane's local time
is reset to 0) and the sample times.  It is used by
:func:`nilpotent.numeric.engines.heyoka_engine.run_heyoka` for everything the
lean loop does not do (several segments, samples on the way, the last partial
batch, batches in which a lane failed).

Its promise is that a trajectory's result (status, steps, end point, samples)
is bit-identical whatever the other lanes of its batch do, which heyoka does
not give by itself: one lane with a non-finite state stops every lane; the
batch's step limit stops every lane; a lane stopped and restarted mid-way is
not bit-identical (heyoka's compensated sums start afresh); a lane already at
its target is stepped again when its double-length time misses the target by
an ulp; and heyoka reports ``step_limit``, not ``time_limit``, for a lane that
took its last step to its target in a call the step limit ended.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from nilpotent.numeric.engines.base import Status

_BLOW_UP, _MAX_STEPS, _NON_FINITE = int(Status.BLOW_UP), int(Status.MAX_STEPS), int(
    Status.NON_FINITE)


def run_chunk(
    ta: Any,
    lo: int,
    hi: int,
    xs: np.ndarray,
    pars: np.ndarray,
    evt_time: np.ndarray,
    evt_kind: np.ndarray,
    segs: int,
    final: np.ndarray,
    samples: np.ndarray,
    info: np.ndarray,
    max_steps: int,
    bound: float,
    outcomes_of_interest: tuple[Any, Any],
) -> None:
    """Integrate trajectories ``lo:hi`` (≤ one SIMD batch) through all their events.

    ``outcomes_of_interest``: heyoka's ``(time_limit, step_limit)`` outcomes.

    A lane with no trajectory (the spare lanes of the last chunk, a stopped
    trajectory) is a copy of a live lane (state, parameters, time, target):
    it computes what that lane computes, so it never stops the SIMD batch on
    its own (heyoka stops every lane when one has a non-finite state).  A
    trajectory is judged only on its own: beyond ``bound`` at one of its own
    events, ``max_steps`` by its own step count, non-finite when it is; so
    neither its status nor its state depends on the other lanes.
    """
    time_limit, _ = outcomes_of_interest
    bs = ta.batch_size
    width = hi - lo
    rows = np.arange(lo, hi)
    # lanes → trajectories; spare lanes (last chunk) copy the chunk's first trajectory
    pad = slice(lo, hi) if width == bs else np.r_[rows, np.full(bs - width, lo)]
    state = ta.state
    par = ta.pars
    state[:] = xs[pad].T
    par[:] = pars[pad, 0].T
    ta.set_time(np.zeros(bs))
    alive = np.ones(bs, dtype=bool)
    alive[width:] = False
    status = np.zeros(bs, dtype=np.int64)
    steps = np.zeros(bs, dtype=np.int64)
    all_lanes = np.arange(width)
    final_only = evt_time.shape[1] == 1
    offset = np.zeros(bs)  # global start time of each lane's current segment
    at = np.zeros(bs)  # local time of each lane's last event
    anyone = True  # some lane is alive
    for e in range(evt_time.shape[1]):
        if not anyone:
            break  # every trajectory of the chunk has stopped
        target = evt_time[pad, e]
        if segs > 1:
            target = target - offset  # local time in the current segment
        everyone = width == bs and bool(alive.all())
        # the live lanes that have not reached their target; one already there (a sample at a
        # segment end or at the end) is not propagated: heyoka would take a tiny step (its
        # double-length time may miss the target by an ulp), which the lean loop does not
        already = alive & (target == at)
        pending = alive & ~already
        held = None  # lanes at their target, set aside until the event: mask, state, par, time
        first = not already.any()  # the first call, every live lane on its way
        while pending.any():
            if not everyone:  # the idle lanes copy the first live lane
                idle = ~alive
                donor = int(np.argmax(alive))
                state[:, idle] = state[:, donor: donor + 1]
                par[:, idle] = par[:, donor: donor + 1]
                t_hi, t_lo = ta.dtime
                ta.set_dtime(np.where(idle, t_hi[donor], t_hi), np.where(idle, t_lo[donor], t_lo))
                target = np.where(idle, target[donor], target)
            # where each lane starts this call: a lane that another one stops on its way (an
            # error, the batch's step limit) goes back there and runs again, uninterrupted (a
            # restart is not bit-identical: heyoka's compensated sums start afresh); a lane
            # that reached its target in an earlier call goes back there too (heyoka would
            # step it again: its double-length time may miss the target by an ulp)
            start_x, start_t = state.copy(), [t.copy() for t in ta.dtime]
            done = np.zeros(bs, dtype=bool) if first else alive & ~pending
            some_done = not first and bool(done.any())
            everyone_on = everyone and first
            # most steps any lane still on its way has taken so far
            used = 0 if e == 0 and everyone_on else int(steps[pending].max())
            ta.propagate_until(target, max_steps=max(max_steps - used, 1))
            outcomes, _, _, taken = zip(*ta.propagate_res, strict=True)
            if (
                outcomes.count(time_limit) == bs
                and used + max(taken) < max_steps
                and not some_done
                and np.abs(state).max() <= bound  # False for NaN
            ):
                steps += taken if everyone_on else np.array(taken) * pending
                break  # the common case: every lane reached its target
            taken = np.array(taken)
            x = state.T
            t_hi, t_lo = (t.copy() for t in ta.dtime)
            finite = np.all(np.isfinite(x), axis=1) & np.isfinite(t_hi) & np.isfinite(t_lo)
            big = np.any(np.abs(np.where(np.isfinite(x), x, 0.0)) > bound, axis=1)
            # heyoka reports step_limit (not time_limit) for a lane that took its last step to
            # the target when the batch's step limit or another lane's error ended the call
            with np.errstate(invalid="ignore"):
                arrived = np.abs((target - t_hi) - t_lo) <= 4 * np.spacing(np.abs(target))
            reached = np.array([o == time_limit for o in outcomes]) | arrived
            # a lane is judged on its own: non-finite, beyond the bound at its event, or out of
            # its own steps; so neither its status nor its state depends on the other lanes
            dead = pending & (~finite | (big & reached)
                              | ((steps + taken >= max_steps) & ~reached))
            stopped = pending & ~reached & ~dead  # by another lane: runs again
            steps += taken * (pending & ~stopped)
            if dead.any():
                status[dead] = np.where(~finite[dead], _NON_FINITE,
                                        np.where(big[dead], _BLOW_UP, _MAX_STEPS))
                idx = np.flatnonzero(dead[:width])
                final[lo + idx] = x[idx]
                alive &= ~dead
                anyone = bool(alive.any())
                everyone = False
            # a lane at its target whose (unwanted) next step is not finite would stop every
            # call: it waits aside, as an idle lane, until the others reach their targets
            sick = done & ~finite
            if sick.any():
                if held is None:
                    held = (np.zeros(bs, dtype=bool), np.empty_like(state), np.empty_like(par),
                            np.zeros((2, bs)))
                held[0][sick] = True
                held[1][:, sick] = start_x[:, sick]
                held[2][:, sick] = par[:, sick]
                held[3][:, sick] = np.array(start_t)[:, sick]
                alive &= ~sick
                everyone = False
            back = (done & ~sick) | stopped
            if back.any():
                state[:, back] = start_x[:, back]
                ok = np.isfinite(t_hi) & np.isfinite(t_lo)  # the others: dead or idle
                ta.set_dtime(np.where(back, start_t[0], np.where(ok, t_hi, 0.0)),
                             np.where(back, start_t[1], np.where(ok, t_lo, 0.0)))
            pending &= alive & ~reached
            first = False
        if held is not None:
            back, held_x, held_p, held_t = held
            alive |= back
            anyone = True
            state[:, back] = held_x[:, back]
            par[:, back] = held_p[:, back]
            t_hi, t_lo = ta.dtime
            ok = np.isfinite(t_hi) & np.isfinite(t_lo)
            ta.set_dtime(np.where(back, held_t[0], np.where(ok, t_hi, 0.0)),
                         np.where(back, held_t[1], np.where(ok, t_lo, 0.0)))
        if not anyone:
            break
        if final_only and everyone:  # one segment, no samples: the common case
            final[lo:hi] = state[:, :width].T
            continue
        at = np.where(alive, target, at)
        live = all_lanes if alive.all() else np.flatnonzero(alive[:width])
        kind = evt_kind[lo + live, e]
        switch = kind < segs - 1
        if switch.any():  # the next segment's inputs
            lanes = live[switch]
            par[:, lanes] = pars[lo + lanes, kind[switch] + 1].T
            offset[lanes] = evt_time[lo + lanes, e]
            at[lanes] = 0.0
            restart = ~alive  # idle lanes (a stopped one's time may be NaN): synced later
            restart[lanes] = True
            t_hi, t_lo = ta.dtime  # the other lanes keep their time exactly
            ta.set_dtime(np.where(restart, 0.0, t_hi), np.where(restart, 0.0, t_lo))
        end = kind == segs - 1
        if end.any():
            final[lo + live[end]] = state[:, live[end]].T
        smp = kind >= segs
        if smp.any():
            samples[lo + live[smp], kind[smp] - segs] = state[:, live[smp]].T
    info[rows, 0] = status[:width]
    info[rows, 1] = steps[:width]
