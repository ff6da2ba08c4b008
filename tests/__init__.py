"""The tests of acmm-qpp.  A package (as is every folder under it), so that the test modules are
imported by their dotted names (``tests.acmm.design.test_sector_lqr``): two files of one
basename in two folders (``tests/acmm/io/test_config.py``, ``tests/qpp/io/test_config.py``) do not
collide, and a test module imports shared helpers as ``from tests.conftest import CONFIGS``."""
