"""acmm_qpp — the base shared by :mod:`acmm` and :mod:`qpp`, knowing neither.

Errors and exit codes, atomic netCDF-4/HDF5, figure and text writing, units, YAML reading and
pydantic validation, work limits, the run lock, a stage's outputs through a staging folder, dotted
overrides, signals, the matplotlib set-up and the command lines' plumbing.  Nothing here imports
``acmm`` or ``qpp`` (``tests/test_layers.py``).
"""
__version__ = "0.1.0"
