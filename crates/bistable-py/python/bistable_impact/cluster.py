"""A ``dask.distributed`` cluster for sweeps, with little upkeep of its own.

Dask's defaults suit interactive work with the dashboard: every process (scheduler, nannies,
workers, client) checks its event loop every 20 ms, each worker samples its own stack every
10 ms for the profiler, and system monitors poll CPU and memory twice a second. An idle
2-worker :class:`distributed.LocalCluster` with those defaults uses about 0.14 CPU seconds per
wall second on this project's 2-core machine, which a sweep pays for as long as it runs (about
10 % of a 60 × 40 map's CPU time). With :data:`LEAN_CONFIG` the same cluster uses about
0.015 (``bench/python_map.py`` measures both; ``--dask-defaults`` for the defaults).

Use :func:`local_cluster` on one machine; on other clusters put :data:`LEAN_CONFIG` in the
workers' and the scheduler's Dask configuration (YAML or environment variables) if their
upkeep matters. The settings change no result, only how often Dask looks at itself:

>>> import bistable_impact as bi
>>> from distributed import Client
>>> with bi.cluster.local_cluster(n_workers=2) as cluster, Client(cluster) as client:
...     df = bi.sweep.map([0.5, 1.0], [0.05, 0.1], client=client, max_periods=300.0)
>>> len(df)
4
"""

from __future__ import annotations

from typing import Any, Dict, Optional

#: Dask settings of a cluster that runs sweeps, not a dashboard session:
#:
#: - ``distributed.admin.tick.interval``: the event-loop health check of every process, 1 s
#:   instead of 20 ms (most of the idle cost; an event loop blocked for longer than
#:   ``distributed.admin.tick.limit``, 3 s, is still reported);
#: - ``distributed.worker.profile.enabled``: no statistical profiler in the workers (the
#:   dashboard's profile page stays empty);
#: - ``distributed.admin.system-monitor.interval``: CPU, memory and network counters every 5 s
#:   instead of 0.5 s (the dashboard's system plots are coarser);
#: - ``distributed.worker.memory.monitor-interval``: the workers' memory limits checked every
#:   1 s instead of 0.1 s (a sweep's tasks hold a few MB).
LEAN_CONFIG: Dict[str, Any] = {
    "distributed.admin.tick.interval": "1s",
    "distributed.worker.profile.enabled": False,
    "distributed.admin.system-monitor.interval": "5s",
    "distributed.worker.memory.monitor-interval": "1s",
}


def local_cluster(
    n_workers: Optional[int] = None,
    threads_per_worker: int = 1,
    processes: bool = True,
    dashboard_address: Optional[str] = None,
    **kwargs: Any,
) -> Any:
    """A :class:`distributed.LocalCluster` started with :data:`LEAN_CONFIG` (its worker
    processes get the same settings).

    Args:
        n_workers: worker processes (``None``: Dask's choice, one per core).
        threads_per_worker: threads per worker (1: each sweep task runs its points as
            batches in SIMD lanes on one core).
        processes: worker processes (``True``) or threads of this process.
        dashboard_address: where the dashboard listens (``None``: no dashboard; e.g.
            ``":8787"`` to have one).
        **kwargs: passed on to :class:`distributed.LocalCluster`.

    Returns:
        The running cluster; use it as a context manager or call ``close()``.

    Raises:
        ImportError: ``dask.distributed`` is not installed.
    """
    import dask
    from distributed import LocalCluster

    with dask.config.set(LEAN_CONFIG):
        return LocalCluster(
            n_workers=n_workers,
            threads_per_worker=threads_per_worker,
            processes=processes,
            dashboard_address=dashboard_address,
            **kwargs,
        )
