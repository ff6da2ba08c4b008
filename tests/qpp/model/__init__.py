"""Tests of :mod:`qpp.model`: ``test_<module>.py`` tests ``qpp/model/<module>.py``."""
