"""Shared fixtures."""

import signal

import pytest

import vtb


def short_case(t_end: float = 0.15):
    """The article's case cut to ``t_end`` (s), observed 8 m into the bridge, two dampers there."""
    c = vtb.paper_config()
    c.solver.t_end = t_end
    c.output.points = [8.0]
    c.tids = vtb.tids_around(c, count=2, x=8.0)
    return c


@pytest.fixture(scope="module")
def short():
    """:func:`short_case` at 0.15 s, one per test module."""
    return short_case()


@pytest.fixture
def default_sigint():
    """Python's own Ctrl-C handler for the test, also when the suite runs where SIGINT is
    ignored (a background job of a non-interactive shell inherits SIG_IGN)."""
    old = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, old)
