"""`serving.runner.wait_for`: the main thread's wait on the simulation hears a stop signal
even when another thread took it."""

import concurrent.futures
import signal
import threading
import time

import pytest

from corobot_drake.serving.runner import SIGNAL_WAIT, wait_for


class _StoppedError(Exception):
    """What the test's signal handler raises (in the main thread, as KeyboardInterrupt is)."""


def _raise_stopped(signum, frame):
    raise _StoppedError


@pytest.mark.skipif(threading.current_thread() is not threading.main_thread(),
                    reason="signal handlers are set, and run, in the main thread only")
def test_a_signal_another_thread_took_stops_the_wait_within_a_slice():
    """The kernel gives a signal sent to a process to any thread not blocking it; Python runs
    the handler in the main thread only, when it next runs Python code, and a main thread
    asleep on an untimed lock (`future.result()`) is not woken by a signal another thread
    took: it heard it only when the future was done. Here the signal is sent to another
    thread (pthread_kill) 0.2 s into the wait, and the future is done only after 5 s: the
    handler's exception ends the wait one slice (`SIGNAL_WAIT`) later, not at 5 s."""
    future: concurrent.futures.Future = concurrent.futures.Future()
    done_late = threading.Timer(5.0, future.set_result, args=(None,))
    taker = threading.Thread(target=time.sleep, args=(0.6,), name="takes-the-signal")
    sends = threading.Timer(0.2, lambda: signal.pthread_kill(taker.ident, signal.SIGUSR1))
    previous = signal.signal(signal.SIGUSR1, _raise_stopped)
    try:
        taker.start()
        done_late.start()
        start = time.monotonic()
        sends.start()
        with pytest.raises(_StoppedError):
            wait_for(future)
        waited = time.monotonic() - start
    finally:
        signal.signal(signal.SIGUSR1, previous)
        for timer in (sends, done_late):
            timer.cancel()
        taker.join()
    assert not future.done()
    # 0.2 s to the signal, then at most a slice; 1 s of slack for a loaded 2-core machine
    assert 0.2 <= waited < 0.2 + SIGNAL_WAIT + 1.0, waited


def test_the_wait_returns_the_result_raises_the_error_and_times_out():
    """Otherwise as `future.result(timeout)`: the value, the future's own exception (even a
    TimeoutError of its own), and TimeoutError after `timeout` s when it is not done."""
    done: concurrent.futures.Future = concurrent.futures.Future()
    threading.Timer(0.25, done.set_result, args=(42,)).start()
    assert wait_for(done) == 42
    failed: concurrent.futures.Future = concurrent.futures.Future()
    failed.set_exception(TimeoutError("the simulation's own"))
    with pytest.raises(TimeoutError, match="the simulation's own"):
        wait_for(failed, timeout=5.0)
    start = time.monotonic()
    with pytest.raises(TimeoutError, match=r"no answer in 0\.3 s"):
        wait_for(concurrent.futures.Future(), timeout=0.3)
    assert 0.3 <= time.monotonic() - start < 0.3 + 1.0
