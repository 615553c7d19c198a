"""Deprecated path: the module is :mod:`vtb.article.tid_optimize`; this alias goes in the next release."""

import sys

from ._moved import moved

sys.modules[__name__] = moved(__name__, "vtb.article.tid_optimize")
