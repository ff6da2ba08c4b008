"""Tests of :mod:`acmm.design`: ``test_<module>.py`` tests ``acmm/design/<module>.py``."""
