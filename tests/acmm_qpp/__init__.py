"""Tests of :mod:`acmm_qpp`: ``test_<module>.py`` tests ``acmm_qpp/<module>.py``."""
