"""Tests of :mod:`acmm.io`: ``test_<module>.py`` tests ``acmm/io/<module>.py``."""
