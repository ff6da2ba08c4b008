"""Tests of :mod:`qpp.design`: ``test_<module>.py`` tests ``qpp/design/<module>.py``."""
