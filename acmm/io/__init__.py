"""Configs, schemas, units and the stage files (``design.h5``, ``sim.h5``) of acmm."""
