"""Dask settings for a cluster that runs acmm sweeps: Dask's own background activity cut to what a
batch of CPU-bound chunks needs (issue 16).

A Dask worker, its nanny and the scheduler keep working while the tasks run: the worker's
statistical profiler interrupts the task thread every 10 ms to walk its stack, every server's
event loop wakes every 20 ms to check that it is not blocked, and every worker's memory is polled
every 100 ms.  Measured on the 2-core machine with a 2-worker ``LocalCluster`` (scheduler and
nannies in the driver's process): ~1.1 s of CPU per 10 s *idle* with Dask's defaults, 0.3 s with
:data:`DASK_SETTINGS`; a sweep task thread runs as fast as a pool worker's, so with as many
workers as cores this background activity is most of what separates the two (docs/performance.md).

The settings change no result (a sweep's table is the same bit for bit under any Dask
configuration); they only make the cluster quieter:

``distributed.worker.profile.enabled: false``
    No statistical profiler (the dashboard's "Profile" page stays empty).
``distributed.admin.tick.interval: 1s``
    The event loop's blocked-loop check every second instead of every 20 ms (the warning for a
    loop blocked longer than ``distributed.admin.tick.limit``, 3 s, still comes).
``distributed.worker.memory.monitor-interval: 1s``
    Worker memory polled every second instead of every 100 ms (the memory limits still apply,
    noticed up to a second later; a sweep case holds a few MB).

They must be in force where each server starts: in the process that creates a ``LocalCluster``::
    import dask, distributed
    from acmm.sweep.dask_settings import DASK_SETTINGS

    with dask.config.set(DASK_SETTINGS):
        cluster = distributed.LocalCluster(n_workers=8, threads_per_worker=1)

or, for ``dask scheduler`` / ``dask worker`` processes, as a YAML file in the Dask config
directory (``~/.config/dask/`` or ``$DASK_CONFIG``) with the text of :func:`dask_settings_yaml`.
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
