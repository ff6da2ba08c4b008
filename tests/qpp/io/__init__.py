"""Tests of :mod:`qpp.io`: ``test_<module>.py`` tests ``qpp/io/<module>.py``."""
