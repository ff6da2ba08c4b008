"""Tests of :mod:`acmm.cli`: ``test_<module>.py`` tests ``acmm/cli/<module>.py``."""
