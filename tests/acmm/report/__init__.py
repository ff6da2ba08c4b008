"""Tests of :mod:`acmm.report`: ``test_<module>.py`` tests ``acmm/report/<module>.py``."""
