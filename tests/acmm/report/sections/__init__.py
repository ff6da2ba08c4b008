"""Tests of :mod:`acmm.report.sections`: ``test_<module>.py`` tests ``acmm/report/sections/<module>.py``."""
