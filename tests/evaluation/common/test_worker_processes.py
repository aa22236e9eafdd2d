"""Worker pools: signals held while workers start, workers that leave signals to their
parent (the batch tests kill such pools: tests/evaluation/trials/test_batch_stop.py)."""

import itertools
import os
import signal

import pytest

from evaluation.common.worker_processes import kill_pool, ordered_map, signals_held, worker_pool


def _signal_state() -> tuple[bool, bool, set[int]]:
    return (
        signal.getsignal(signal.SIGINT) is signal.SIG_IGN,
        signal.getsignal(signal.SIGTERM) is signal.SIG_IGN,
        set(signal.pthread_sigmask(signal.SIG_BLOCK, [])),
    )


def test_a_signal_in_a_held_block_is_delivered_when_it_ends():
    reached = False
    with pytest.raises(KeyboardInterrupt):
        with signals_held():
            os.kill(os.getpid(), signal.SIGINT)
            os.kill(os.getpid(), signal.SIGINT)
            reached = True
    assert reached
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_workers_ignore_both_signals_and_block_none():
    pool = worker_pool(1)
    try:
        assert pool.submit(_signal_state).result(timeout=60) == (True, True, set())
    finally:
        kill_pool(pool)


def test_ordered_map_keeps_the_order_and_a_bounded_window():
    drawn = []

    def endless():
        for k in itertools.count():
            drawn.append(k)
            yield -k

    pool = worker_pool(2)
    try:
        results = ordered_map(pool, abs, endless(), window=4)
        assert list(itertools.islice(results, 10)) == list(range(10))
        assert len(drawn) <= 10 + 4  # never more than the window ahead of what was yielded
        assert list(ordered_map(pool, abs, [-3, 1, -2], window=1)) == [3, 1, 2]
    finally:
        kill_pool(pool)
    with pytest.raises(ValueError, match="window 0: expected at least 1"):
        next(ordered_map(pool, abs, [1], window=0))
