"""qpp — quantitative pole placement: L∞ tracking in the sense of spheres for Lure systems.

Implements Part III of NASA CR-185644 (Parlos & Jayasuriya, 1990), chapters 9–14 (ch. 9–14).
"""
__version__ = "0.1.0"

#: The data package of the configs shipped with the distribution (the source tree's ``configs/``
#: folder, mapped by ``pyproject.toml``), looked up by name with importlib.resources.
PACKAGED_CONFIGS = "acmm.configs"
#: The top-level sections of a qpp config: a config with one of them is a qpp config.
CONFIG_SECTIONS = ("plant", "nonlinearity", "hinf", "spheres")
