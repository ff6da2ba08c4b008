"""common — the base shared by :mod:`acmm` and :mod:`qpp`.

Errors and exit codes, atomic HDF5/figure/text writing and its netCDF layout, units, YAML
reading and validation, work limits, the run lock, output ownership, error hints, dotted
overrides, worker teardown and the matplotlib style.  Nothing here imports ``acmm``, ``qpp`` or
``cli`` (``tests/test_layers.py``).
"""
__version__ = "0.1.0"

#: The data package holding the configs shipped with the distribution (the source tree's
#: ``configs/`` folder, mapped by ``pyproject.toml``); a name, looked up with importlib.resources.
PACKAGED_CONFIGS = "acmm.configs"
