"""The `alone` marker, a pytest plugin (tests/conftest.py takes its hooks; `-p alone` loads it).

Under pytest-xdist (`pytest -n`, the README's command) a test that measures what the other
workers' load would change (a command's peak memory: its threads' tiles are at their peak
together only on an idle machine) runs with no test of another worker beside it.  Every test
holds a shared lock on a file of the run from its setup to its teardown, an `alone` one an
exclusive lock; a turnstile lock, held by an `alone` test while it waits, keeps the other
workers' next tests from slipping in before it.  Without xdist it does nothing.
"""

from __future__ import annotations

import contextlib
import fcntl
import os

import pytest


def pytest_configure(config):
    config.addinivalue_line("markers", "alone: under pytest-xdist, runs with no other "
                                       "worker's test beside it (tests/alone.py)")


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_protocol(item, nextitem):
    with _turn(item):
        yield


@contextlib.contextmanager
def _turn(item):
    """The lock an xdist worker's test holds while it runs: shared, or exclusive for an
    `alone` test; nothing without xdist."""
    if "PYTEST_XDIST_WORKER" not in os.environ:
        yield
        return
    run = item.config._tmp_path_factory.getbasetemp().parent    # the run's, shared by workers
    with open(run / "turnstile.lock", "a") as gate, open(run / "room.lock", "a") as room:
        alone = item.get_closest_marker("alone") is not None
        fcntl.flock(gate, fcntl.LOCK_EX)
        if not alone:
            fcntl.flock(gate, fcntl.LOCK_UN)
        fcntl.flock(room, fcntl.LOCK_EX if alone else fcntl.LOCK_SH)
        if alone:
            fcntl.flock(gate, fcntl.LOCK_UN)
        try:
            yield
        finally:
            fcntl.flock(room, fcntl.LOCK_UN)
