"""servotune.interrupt: Ctrl-C sets a flag that survives native code swallowing it, worker
pools end at once, and the command exits 130 with one line."""

import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from servotune import interrupt

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(autouse=True)
def _no_interrupt_left_over():
    """A timer of a test that fires after it ended (a loaded machine) must not interrupt the
    tests that follow: each test's timers are cancelled and the flag cleared at its end."""
    before = set(threading.enumerate())
    yield
    for t in threading.enumerate():
        if isinstance(t, threading.Timer) and t not in before:
            t.cancel()
            t.join()
    interrupt._flag.clear()


def _sigint_after(seconds: float) -> threading.Timer:
    timer = threading.Timer(seconds, os.kill, (os.getpid(), signal.SIGINT))
    timer.start()
    return timer


def _rosenbrock_solver(n: int = 2000, callback=None):
    import casadi as ca

    x = ca.MX.sym("x", n)
    f = ca.sum1(100 * (x[1:] - x[:-1] ** 2) ** 2 + (1 - x[:-1]) ** 2)
    options = {"ipopt.print_level": 0, "print_time": False, "ipopt.sb": "yes",
               "ipopt.max_iter": 100_000, "ipopt.tol": 1e-30, "ipopt.acceptable_iter": 0}
    if callback is not None:
        options["iteration_callback"] = callback
    return ca.nlpsol("rosenbrock", "ipopt", {"x": x, "f": f}, options), n


def test_ctrl_c_sets_the_flag_and_raises():
    with interrupt.handling():
        assert not interrupt.requested()
        with pytest.raises(KeyboardInterrupt):
            _sigint_after(0.05)
            time.sleep(5)
        assert interrupt.requested()
        with pytest.raises(interrupt.Interrupted) as info:
            interrupt.check("tuning, start 2 of 4")
        assert info.value.what == "tuning, start 2 of 4"
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_ipopt_swallows_ctrl_c_but_the_flag_tells():
    # casadi's IPOPT interface stops on Ctrl-C and returns a failed status instead of raising;
    # the flag is what lets the tuner end the run instead of trying the next start
    solver, n = _rosenbrock_solver()
    with interrupt.handling():
        _sigint_after(0.5)
        solver(x0=[-1.2] * n)
        stats = solver.stats()
        assert stats["success"] is False and stats["iter_count"] < 100_000
        assert interrupt.requested()
        with pytest.raises(interrupt.Interrupted):
            interrupt.check("tuning")


def test_the_iteration_callback_stops_ipopt_when_the_flag_is_set():
    n = 2000
    callback = interrupt.casadi_iteration_callback(n_x=n)
    solver, _ = _rosenbrock_solver(n, callback)
    with interrupt.handling():
        threading.Timer(0.5, interrupt._flag.set).start()  # as a Ctrl-C elsewhere would
        solver(x0=[-1.2] * n)
        stats = solver.stats()
    assert stats["return_status"] == "User_Requested_Stop"
    interrupt.clear()


def _sleep(seconds):
    time.sleep(seconds)
    return seconds


def test_a_pool_ends_its_workers_when_interrupted():
    with pytest.raises(KeyboardInterrupt):
        with interrupt.process_pool(2) as pool:
            futures = [pool.submit(_sleep, 60.0) for _ in range(2)]
            while not all(f.running() for f in futures):
                time.sleep(0.05)
            processes = list(pool._processes.values())
            raise KeyboardInterrupt
    assert processes and not any(p.is_alive() for p in processes)


def test_the_command_exits_130_on_ctrl_c_with_one_line_and_no_partial_results(tmp_path):
    out = tmp_path / "out"
    command = [sys.executable, "-c", "import sys; from servotune.cli import main; "
               "sys.exit(main(sys.argv[1:]))", "table3", str(ROOT / "models" / "paper_x_axis"),
               "--workers", "2", "--duration", "600", "--out", str(out)]
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                               text=True, cwd=tmp_path)
    time.sleep(8.0)  # loaded and simulating (15 trials of 600 s sweeps take minutes)
    assert process.poll() is None
    process.send_signal(signal.SIGINT)
    stdout, stderr = process.communicate(timeout=60)
    assert process.returncode == 130, stderr
    lines = [line for line in stderr.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("servotune table3: interrupted"), stderr
    assert "nothing was written" in lines[0] and stdout == ""
    assert not out.exists() or not any(out.iterdir())


def _schur_interrupted_in_its_callback():
    """Ctrl-C pressed while scipy's Schur sort callback (f2py) runs, as in a loop analysis."""
    from scipy.linalg import schur

    calls = []

    def select(x):
        calls.append(x)
        if len(calls) == 10:
            os.kill(os.getpid(), signal.SIGINT)  # delivered at the next bytecode, in here
        return x.real < 0

    a = np.random.default_rng(1).normal(size=(30, 30))
    with pytest.raises(KeyboardInterrupt):
        schur(a, output="complex", sort=select)


def test_native_noise_after_ctrl_c_is_silenced(capfd):
    # scipy's f2py callbacks print "capi_return is NULL" / "Call-back ... failed." on fd 2 when
    # Ctrl-C lands inside them; the command wants only its own line
    with interrupt.handling(silence_native_stderr=True):
        _schur_interrupted_in_its_callback()
        os.write(2, b"still silenced\n")
        interrupt.restore_stderr()
        os.write(2, b"after restore\n")
    assert capfd.readouterr().err == "after restore\n"


def test_without_silencing_the_noise_is_there(capfd):
    # the reference: the same interruption without silence_native_stderr
    with interrupt.handling():
        _schur_interrupted_in_its_callback()
    assert "Call-back" in capfd.readouterr().err
