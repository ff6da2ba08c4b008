"""Dask settings for a cluster that runs acmm sweeps: Dask's own background activity cut to what a
batch of CPU-bound chunks needs (issue 16).  They change no result (a sweep's table is the same
bit for bit under any Dask configuration); they only make the cluster quieter: no statistical
profiler (every 10 ms on the task thread), the blocked-event-loop check every second (not every
20 ms; the warning after ``distributed.admin.tick.limit`` still comes) and worker memory polled
every second (not every 100 ms).  Measured on the 2-core machine with a 2-worker
``LocalCluster``: ~1.1 s of CPU per 10 s idle with Dask's defaults, 0.3 s with
:data:`DASK_SETTINGS` (docs/performance.md).

They must be in force where each server starts: ``with dask.config.set(DASK_SETTINGS):`` around
the creation of a ``LocalCluster``, or, for ``dask scheduler`` / ``dask worker`` processes, the
text of :func:`dask_settings_yaml` as a file in the Dask config directory (``~/.config/dask/`` or
``$DASK_CONFIG``); docs/howto/sweeps.md shows both.
"""
from __future__ import annotations
import yaml

#: dotted Dask config keys and values for a cluster that runs acmm sweeps (module docstring)
DASK_SETTINGS = {
    "distributed.worker.profile.enabled": False,
    "distributed.admin.tick.interval": "1s",
    "distributed.worker.memory.monitor-interval": "1s",
}


def dask_settings_yaml() -> str:
    """:data:`DASK_SETTINGS` as a Dask config file (nested YAML), for ``~/.config/dask/acmm.yaml``.

    Returns
    -------
    str
        The YAML text.
    """
    tree: dict = {}
    for key, value in DASK_SETTINGS.items():
        *parents, leaf = key.split(".")
        node = tree
        for p in parents:
            node = node.setdefault(p, {})
        node[leaf] = value
    return yaml.safe_dump(tree, sort_keys=True)
