"""Tests of :mod:`acmm.sweep`: ``test_<module>.py`` tests ``acmm/sweep/<module>.py``."""
