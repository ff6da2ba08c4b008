"""Tests of :mod:`acmm_qpp.cli`: ``test_<module>.py`` tests ``acmm_qpp/cli/<module>.py``."""
