"""The machine a generated report was measured on: one line for its header, so that every run
time in docs/ carries the machine and the load it was taken under (the machine may be shared)."""

from __future__ import annotations

import os
import platform
import time


def describe() -> str:
    """``x86_64, 2 cores, Python 3.11.7, load 1.20/1.35/1.50 (1, 5, 15 min averages) on
    2026-12-03``: the machine, the interpreter, the load averages now and today's date."""
    try:
        load = "load " + "/".join(f"{v:.2f}" for v in os.getloadavg()) + " (1, 5, 15 min averages)"
    except OSError:  # not on every platform
        load = "load not available"
    return (f"{platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}, {load} "
            f"on {time.strftime('%Y-%m-%d')}")
