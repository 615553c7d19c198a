"""Shared fixtures."""

import signal

import pytest


@pytest.fixture
def default_sigint():
    """Python's own Ctrl-C handler for the test, also when the suite runs where SIGINT is
    ignored (a background job of a non-interactive shell inherits SIG_IGN)."""
    old = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, old)
