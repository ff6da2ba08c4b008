"""Tests of :mod:`acmm`: ``test_<module>.py`` tests ``acmm/<module>.py``."""
