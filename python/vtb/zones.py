"""Deprecated path: the module is :mod:`vtb.config.zones`; this alias goes in the next release."""

import sys

from ._moved import moved

sys.modules[__name__] = moved(__name__, "vtb.config.zones")
