"""The GIL is released while a function runs: threads evaluate concurrently, and a
pure-Python thread keeps running during a long batch."""

import threading
import time

import numpy as np

LONG_BATCH = 100_000  # knots: long enough to be seen from another thread


def test_two_threads_evaluating_at_once_both_finish_with_right_values(rnea):
    rng = np.random.default_rng(3)
    inputs = [{name: rng.uniform(-1, 1, (2000, 7)) for name in ("q", "v", "a")} for _ in range(2)]
    expected = [rnea(**x)["jacobian"] for x in inputs]
    results = [None, None]

    def work(i):
        for _ in range(5):
            results[i] = rnea(**inputs[i])["jacobian"]

    threads = [threading.Thread(target=work, args=(i,)) for i in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(timeout=60)
    assert not any(t.is_alive() for t in threads)
    for i in range(2):
        np.testing.assert_array_equal(results[i], expected[i])


def test_a_python_thread_runs_while_a_long_batch_evaluates(crba):
    q = np.random.default_rng(5).uniform(-1, 1, (LONG_BATCH, 7))
    out = {"value": np.empty((LONG_BATCH, 7, 7))}
    ticks_during = []
    inside = threading.Event()
    done = threading.Event()

    def count_ticks():
        count = 0
        while not done.is_set():
            count += 1
            if inside.is_set():
                ticks_during.append(count)
            time.sleep(0)

    ticker = threading.Thread(target=count_ticks)
    ticker.start()
    start = time.perf_counter()
    inside.set()
    crba(q=q, out=out)
    inside.clear()
    elapsed = time.perf_counter() - start
    done.set()
    ticker.join(timeout=10)
    # A thread that held the GIL for the whole batch would let the counter move at most
    # once per switch interval (5 ms); released, it counts freely meanwhile.
    assert elapsed > 0
    assert len(ticks_during) > max(10, 2 * elapsed / 0.005), (len(ticks_during), elapsed)
