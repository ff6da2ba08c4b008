"""Tests of :mod:`acmm.plots`: ``test_<module>.py`` tests ``acmm/plots/<module>.py``."""
