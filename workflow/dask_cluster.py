"""The Dask cluster a sweep runs on: local, an existing scheduler, or dask-jobqueue.

Only this module talks to Dask; the sweep hands it functions and arguments and gets
results back as they complete.
"""

from __future__ import annotations

import logging
import os
from collections.abc import Callable, Iterator

from rotorflow.errors import CaseError, RotorflowError

from .sweep_file import JOBQUEUE, ClusterSpec

log = logging.getLogger(__name__)

#: Seconds to wait for a named scheduler before giving up.
SCHEDULER_TIMEOUT_S = 20


def local_workers(spec: ClusterSpec, n_points: int) -> int:
    return spec.workers or max(1, min(os.cpu_count() or 1, n_points))


def jobqueue_cluster(spec: ClusterSpec):
    """The dask-jobqueue cluster a sweep names (not yet scaled: no job submitted)."""
    try:
        import dask_jobqueue
    except ImportError as exc:
        raise CaseError(f"[cluster] jobqueue = '{spec.jobqueue}' needs dask-jobqueue "
                        "(pip install dask-jobqueue)") from exc
    try:
        return getattr(dask_jobqueue, JOBQUEUE[spec.jobqueue])(**spec.options)
    except (TypeError, ValueError) as exc:
        raise CaseError(f"[cluster.options] of the {spec.jobqueue} cluster: {exc}") from None


# The local workers' environment.  Each point is single-threaded numpy: no
# oversubscription from BLAS threads.  Dask's nanny sets MALLOC_TRIM_THRESHOLD_=65536,
# which also fixes glibc's mmap threshold at 128 KiB: every array of the geometry's
# ~1e4-1e5 knots is then mapped and unmapped anew (page faults; measured: a point's
# geometry stage 3 s on a worker against 0.2 s in one process, the 58-point example
# sweep 197 s).  Trimming above 128 MiB and mapping above 32 MiB keep them in the heap.
WORKER_ENV = {"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1",
              "MALLOC_TRIM_THRESHOLD_": str(128 << 20), "MALLOC_MMAP_THRESHOLD_": str(32 << 20)}


def open_client(spec: ClusterSpec, n_points: int):
    """A Dask client for the sweep, and a closer."""
    try:
        from dask.distributed import Client, LocalCluster
    except ImportError as exc:
        raise RotorflowError("sweeps run on Dask: pip install 'dask[distributed]' "
                             "(or run with --serial)") from exc

    if not log.isEnabledFor(logging.INFO):  # Dask logs every worker's start and stop
        logging.getLogger("distributed").setLevel(logging.WARNING)

    if spec.address:
        try:
            client = Client(spec.address, timeout=SCHEDULER_TIMEOUT_S)
        except (OSError, TimeoutError) as exc:
            raise RotorflowError(f"cannot reach the Dask scheduler at {spec.address}: "
                                 f"{exc}") from None
        return client, client.close
    if spec.jobqueue:
        cluster = jobqueue_cluster(spec)
        cluster.scale(jobs=spec.jobs)
    else:
        import dask

        # glibc reads its MALLOC_ variables when the process starts: they must be in the
        # nanny's pre-spawn environment, which its env argument is not
        malloc = {f"distributed.nanny.pre-spawn-environ.{k}": v
                  for k, v in WORKER_ENV.items() if k.startswith("MALLOC_")}
        with dask.config.set(malloc):
            cluster = LocalCluster(n_workers=local_workers(spec, n_points),
                                   threads_per_worker=spec.threads_per_worker,
                                   processes=True, dashboard_address=None,
                                   silence_logs=logging.ERROR, env=WORKER_ENV)
    client = Client(cluster)

    def close():
        client.close()
        cluster.close()

    return client, close


def as_completed_results(client, fn: Callable, jobs: list[tuple[str, tuple]], prefix: str
                         ) -> Iterator[tuple[str, object, BaseException | None]]:
    """Run ``fn(*args)`` for every ``(name, args)`` of ``jobs`` on the cluster; yield
    ``(name, result, None)``, or ``(name, None, error)`` when the task itself failed
    (a lost worker, say), in the order they complete."""
    from dask.distributed import as_completed

    futures = {client.submit(fn, *args, key=f"{prefix}-{name}", pure=False): name
               for name, args in jobs}
    for fut in as_completed(futures):
        try:
            yield futures[fut], fut.result(), None
        except Exception as exc:  # noqa: BLE001 - reported per task by the caller
            yield futures[fut], None, exc
