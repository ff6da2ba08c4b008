"""Names shared by every part of the report: section keys and titles, ``--fast`` length, timing datasets,
the axis names."""
from __future__ import annotations

#: stair-case length of ``--fast`` (orbits): one dwell per design point of the 12-point schedule
FAST_ORBITS = 13.0
#: names of the three body control axes, in order (x, y, z)
AXES = ("roll", "pitch", "yaw")
#: datasets that hold timings, excluded from determinism hashes ("timestamps aside")
TIMING_DATASETS = ("wall_time",)

SECTIONS = [
    ("table1", "Table 1: configurations and torque-equilibrium attitudes"),
    ("schedule", "Gain schedules and pole maps (Figs 5.3–5.26)"),
    ("claim1", "Claim 1: MB3 coupled vs cross-inertia-free design (Figs 6.2–6.13)"),
    ("staircase", "Claim 2: the MB3 → AC stair-case (Figs 6.14–6.30)"),
    ("robustness", "±30 % inertia robustness"),
    ("qpp13", "QPP chapter 13: SISO Lure example"),
    ("qpp14", "QPP chapter 14: two-DOF manipulator"),
    ("errata", "Errata: misprints, corrections and evidence"),
    ("printed", "Printed numbers: reproduced or explained"),
    ("determinism", "Determinism"),
    ("provenance", "Provenance"),
]


#: the report's stair-cases (config keys of :func:`acmm.report.gather.report_configs`): the
#: packaged one, on the report's route, in the report's quadratic form
STAIRCASES = ("staircase", "staircase_lqr", "staircase_quadratic")
