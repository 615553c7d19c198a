"""Deprecated path: the module is :mod:`vtb.studies.journal`; this alias goes in the next release."""

import sys

from ._moved import moved

sys.modules[__name__] = moved(__name__, "vtb.studies.journal")
