"""Ctrl-C and SIGTERM at any moment (issue 22, item 4): exit 130 / 143, no traceback,
nothing half-written; the signal is raised only at a safe point (never inside an import)
and a swallowed exception still ends the run.

The subprocess test starts each run with SIGINT and SIGTERM *blocked* (inherited through
``exec``): whatever the machine's load, a signal sent at any delay then reaches the
program's own handler (``nilpotent.interrupts.install`` unblocks them once it is in
place), never the default action during the interpreter's start-up, which no program
controls.  The runs go in parallel so the whole test costs a few seconds.
"""

from __future__ import annotations

import csv
import json
import os
import signal
import subprocess
import sys
import textwrap
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

from nilpotent import interrupts

CLI = [sys.executable, "-m", "nilpotent"]
ENV = {**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)}
SIGNALS = {signal.SIGINT: 130, signal.SIGTERM: 143}


def _interrupt(args: list[str], delay: float, signum: int, folder: Path, twice: bool = False
               ) -> tuple[int, str, str]:
    # the child inherits the blocked signals from this (pool) thread's mask, through
    # fork and exec (no preexec_fn: it is unsafe with threads)
    old = signal.pthread_sigmask(signal.SIG_BLOCK, set(SIGNALS))
    try:
        proc = subprocess.Popen(
            [*CLI, *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=ENV,
            cwd=folder,
        )
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)
    time.sleep(delay)
    proc.send_signal(signum)
    if twice:  # a second signal during the clean-up must not abort the interpreter
        time.sleep(0.05)
        with_pid = proc.poll() is None
        if with_pid:
            proc.send_signal(signal.SIGTERM)
    stdout, stderr = proc.communicate(timeout=300)
    return proc.returncode, stdout, stderr


# delays from 0 to 3 s: the interpreter's start, the imports (typer, sympy, flint,
# symengine; heyoka and scipy for the sweep), the work, the writing of the output
ANALYZE = [(0.0, signal.SIGINT), (0.05, signal.SIGTERM), (0.15, signal.SIGINT),
           (0.3, signal.SIGTERM), (0.6, signal.SIGINT), (1.0, signal.SIGTERM),
           (2.0, signal.SIGINT), (3.0, signal.SIGTERM)]
SWEEP = [(0.0, signal.SIGTERM), (0.1, signal.SIGINT), (0.4, signal.SIGTERM),
         (0.8, signal.SIGINT), (1.5, signal.SIGTERM), (2.2, signal.SIGINT),
         (3.0, signal.SIGTERM)]


def _check_sweep(code: int, stdout: str, folder: Path) -> None:
    out = folder / "rows.csv"
    result = json.loads(stdout)  # one JSON object, whatever the moment
    if code == 0:  # finished before the signal: the whole file, the result
        assert result["schema"] == "nilpotent/sweep@1"
        text = out.read_text()
        rows = list(csv.reader(text.splitlines()))
        assert text.endswith("\n") and len(rows) > 1
        assert {len(row) for row in rows} == {len(rows[0])}  # whole rows only
    else:
        assert "error" in result or out.exists(), result  # result printed, then the signal
        if "error" in result:
            assert result["error"]["kind"] == "interrupted"
            assert not out.exists()
    # never a temporary left behind, whatever the outcome
    assert [p.name for p in folder.iterdir() if p.name != "rows.csv"] == []


def test_a_signal_at_any_moment_gives_130_or_143_and_leaves_nothing_half_written(tmp_path):
    jobs = []
    for k, (delay, signum) in enumerate(ANALYZE):
        json_out = ["--json"] if k % 2 else []  # human output and --json alike
        jobs.append(("analyze", ["analyze", "unicycle", *json_out], delay, signum, False, k))
    for k, (delay, signum) in enumerate(SWEEP):
        jobs.append(("sweep", ["sweep", "unicycle", "--bracket", "1,2", "--samples", "40",
                               "--radius", "0.1", "--out", "rows.csv", "--json"],
                     delay, signum, delay in (1.5, 3.0), k))

    def one(job):
        name, args, delay, signum, twice, k = job
        folder = tmp_path / f"{name}-{k}"
        folder.mkdir()
        return job, folder, _interrupt(args, delay, signum, folder, twice)

    with ThreadPoolExecutor(max_workers=6) as pool:
        results = list(pool.map(one, jobs))
    for (name, args, delay, signum, _twice, _k), folder, (code, stdout, stderr) in results:
        where = f"{name} at {delay} s ({signal.Signals(signum).name}): exit {code}\n{stderr}"
        assert code in (0, SIGNALS[signum]), where
        assert "Traceback" not in stderr, where
        assert "Fatal Python error" not in stderr, where
        if code != 0:
            assert "interrupted" in stderr or "terminated" in stderr or "interrupted" in stdout, (
                where)
        if name == "sweep":
            _check_sweep(code, stdout, folder)
        elif "--json" in args:
            result = json.loads(stdout)  # one JSON object: the result or the interruption
            assert code == 0 or "bracket_generating" in result or (
                result["error"]["kind"] == "interrupted"), where
            assert code != 0 or "bracket_generating" in result, where


def test_the_entry_point_loads_nothing_heavy_before_its_handlers():
    import tomllib

    project = tomllib.loads((Path(__file__).parents[1] / "pyproject.toml").read_text())
    assert project["project"]["scripts"]["nilpotent"] == "nilpotent.entry:run"
    heavy = ("typer", "rich", "sympy", "symengine", "flint", "numpy", "scipy", "heyoka",
             "numba", "matplotlib", "ompl")
    code = ("import sys, nilpotent.entry, nilpotent.__init__; "
            f"print(','.join(m for m in {heavy!r} if m in sys.modules))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          env=ENV, check=True, timeout=120)
    assert done.stdout.strip() == ""


# --- the mechanism, in this process ------------------------------------------------------
@pytest.fixture
def handlers():
    if threading.current_thread() is not threading.main_thread():
        pytest.skip("signal handlers are installed in the main thread only")
    if any(signal.getsignal(s) == signal.SIG_IGN for s in SIGNALS):
        pytest.skip("this process was started with SIGINT or SIGTERM ignored")
    assert interrupts.install()
    try:
        yield
    finally:
        interrupts.uninstall()


def _wait_for_interrupt(seconds: float = 10.0) -> None:
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        time.sleep(0.005)


def test_a_signal_inside_an_import_is_raised_after_it(handlers, tmp_path, monkeypatch):
    (tmp_path / "slow_module_for_signals.py").write_text(textwrap.dedent("""
        import os, signal, time
        os.kill(os.getpid(), signal.SIGTERM)
        end = time.monotonic() + 0.2
        while time.monotonic() < end:  # bytecodes run: the handler is called here
            pass
        DONE = True
    """))
    monkeypatch.syspath_prepend(str(tmp_path))
    caught = None
    try:
        import slow_module_for_signals  # noqa: F401

        _wait_for_interrupt()
    except interrupts.Terminated as exc:
        interrupts.close()  # (in the except block: nothing is raised again before this)
        caught = exc
    assert isinstance(caught, interrupts.Terminated)
    assert sys.modules.pop("slow_module_for_signals").DONE  # the import finished whole
    assert interrupts.pending() == signal.SIGTERM
    assert interrupts.exit_code() == 143


def test_a_swallowed_interrupt_is_raised_again(handlers):
    seen = []
    try:
        try:
            os.kill(os.getpid(), signal.SIGINT)
            _wait_for_interrupt()
        except BaseException:  # what a bare ``except:`` in compiled code does
            seen.append("swallowed")
        _wait_for_interrupt()  # raised again (by the helper thread): not lost
    except interrupts.Interrupted:
        interrupts.close()
        seen.append("raised again")
    assert seen == ["swallowed", "raised again"]
    assert interrupts.exit_code() == 130


def test_a_checkpoint_raises_a_swallowed_interrupt(handlers, monkeypatch):
    monkeypatch.setattr(interrupts, "RETRY", 60.0)  # no help from the thread here
    seen = []
    try:
        try:
            os.kill(os.getpid(), signal.SIGTERM)
            _wait_for_interrupt()
        except BaseException:
            seen.append("swallowed")
        interrupts.checkpoint()
    except interrupts.Terminated:
        interrupts.close()
        seen.append("checkpoint")
    assert seen == ["swallowed", "checkpoint"]


def test_a_second_signal_during_the_clean_up_is_recorded_not_raised(handlers):
    cleaned = False
    try:
        try:
            os.kill(os.getpid(), signal.SIGTERM)
            _wait_for_interrupt()
        finally:
            os.kill(os.getpid(), signal.SIGINT)  # while the first is being handled
            time.sleep(0.1)
            for _ in range(10_000):  # bytecodes: the handler runs, and does not raise
                pass
            cleaned = True
    except interrupts.Terminated:
        interrupts.close()
    assert cleaned
    assert interrupts.pending() == signal.SIGTERM  # the first signal decides: 143
    os.kill(os.getpid(), signal.SIGTERM)
    time.sleep(0.1)  # closed: recorded only, nothing raised
    interrupts.checkpoint()


def test_a_deferred_block_is_never_cut(handlers):
    steps = []
    try:
        with interrupts.deferred():
            os.kill(os.getpid(), signal.SIGINT)
            for _ in range(100_000):
                pass
            steps.append("first")
            time.sleep(0.1)
            steps.append("second")
        steps.append("after the block")
    except interrupts.Interrupted:
        interrupts.close()
    assert steps == ["first", "second"]


def test_checkpoints_are_free_without_handlers():
    interrupts.checkpoint()  # library use: nothing installed, nothing raised
    assert interrupts.pending() is None


def test_an_interrupt_raised_where_python_cannot_propagate_it_prints_nothing(capsys):
    """A signal handled inside a weakref callback or ``__del__`` (the garbage collector
    runs them at any moment) raises where Python can only report it as "Exception
    ignored in": while the handlers are installed that report is dropped (the record
    stays, and the retry thread delivers the interrupt again); other unraisable
    exceptions are still reported."""
    import types

    from nilpotent import interrupts

    owned = interrupts.install()
    try:
        hook = sys.unraisablehook
        hook(types.SimpleNamespace(exc_type=interrupts.Terminated,
                                   exc_value=interrupts.Terminated(), exc_traceback=None,
                                   err_msg=None, object=None))
        assert capsys.readouterr().err == ""
        seen = []
        previous = interrupts._state["unraisablehook"]  # what was there before install
        interrupts._state["unraisablehook"] = seen.append
        try:
            other = types.SimpleNamespace(exc_type=ValueError, exc_value=ValueError("x"),
                                          exc_traceback=None, err_msg=None, object=None)
            hook(other)
        finally:
            interrupts._state["unraisablehook"] = previous
        assert seen == [other]
    finally:
        if owned:
            interrupts.uninstall()
