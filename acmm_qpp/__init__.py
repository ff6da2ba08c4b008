"""acmm_qpp — the base shared by :mod:`acmm` and :mod:`qpp`, knowing neither.

Errors and exit codes, atomic netCDF-4/HDF5, figure and text writing, units, YAML reading and
validation, work limits, the run lock, a stage's outputs through a staging folder, error hints,
dotted overrides, worker teardown and the matplotlib style.  Nothing here imports ``acmm``, ``qpp`` or
``cli`` (``tests/test_layers.py``).
"""
__version__ = "0.1.0"
