"""Tests of :mod:`acmm.stages`: ``test_<module>.py`` tests ``acmm/stages/<module>.py``."""
