"""Tests of :mod:`qpp`: ``test_<module>.py`` tests ``qpp/<module>.py``."""
