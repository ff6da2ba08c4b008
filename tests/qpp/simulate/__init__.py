"""Tests of :mod:`qpp.simulate`: ``test_<module>.py`` tests ``qpp/simulate/<module>.py``."""
