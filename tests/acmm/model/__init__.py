"""Tests of :mod:`acmm.model`: ``test_<module>.py`` tests ``acmm/model/<module>.py``."""
