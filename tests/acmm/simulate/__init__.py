"""Tests of :mod:`acmm.simulate`: ``test_<module>.py`` tests ``acmm/simulate/<module>.py``."""
