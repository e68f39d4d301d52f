"""The runs of a sweep or a benchmark on a Dask cluster instead of this machine's cores.

Every parallel run of :mod:`fhslam.experiments` (:func:`~fhslam.experiments.compare.slam_sweep`,
:func:`~fhslam.experiments.robustness.log_sweep`, the draws of
:func:`~fhslam.experiments.benchmark.run_benchmark`) goes through :class:`joblib.Parallel`: on
this machine, one worker process per core. Inside :func:`dask_cluster`, joblib hands the runs
to the workers of a Dask cluster (``dask.distributed``, installed with ``pip install
'fhslam[cluster]'``) whose scheduler is at the given address; the results come back in the
same order, the same numbers, with the same progress bar. The cluster's workers need fhslam
installed (the same version) and the data the runs read: a log is read here and sent to them,
a simulated world is made by each worker. The command line: ``fhslam sweep ... --scheduler
ADDRESS`` and ``fhslam benchmark --scheduler ADDRESS``.

Example (a cluster on this machine; on many machines, ``dask scheduler`` on one and ``dask
worker tcp://HOST:8786`` on each)::

    from distributed import LocalCluster
    from fhslam.experiments.cluster import dask_cluster
    from fhslam.experiments.compare import slam_sweep

    with LocalCluster(n_workers=4) as cluster, dask_cluster(cluster.scheduler_address):
        runs = slam_sweep("paper", seeds=range(100), methods=("graph",))
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager

from fhslam.errors import InputError

__all__ = ["dask_cluster"]


@contextmanager
def dask_cluster(address: str, timeout: float = 10.0) -> Iterator[object]:
    """Run :mod:`joblib`'s parallel runs on the Dask cluster whose scheduler is at
    ``address`` (e.g. ``tcp://10.0.0.5:8786``) while the block lasts.

    Parameters
    ----------
    address : str
        The scheduler's address.
    timeout : float
        Seconds to wait for the scheduler to answer.

    Yields
    ------
    distributed.Client
        The client, connected (closed when the block ends).

    Raises
    ------
    InputError
        Without ``dask.distributed`` installed, for an ``address`` that is not one, or when
        no scheduler answers at it within ``timeout`` seconds: before any run.
    """
    try:
        from distributed import Client
    except ImportError:
        raise InputError(
            "--scheduler: running on a Dask cluster needs dask.distributed: "
            "pip install 'fhslam[cluster]'"
        ) from None
    from joblib import parallel_config

    try:
        client = Client(address, timeout=timeout)
    except (ValueError, TypeError) as e:  # not an address
        raise InputError(f"--scheduler {address!r}: not a scheduler's address ({e})") from None
    except (OSError, TimeoutError) as e:
        why = str(e).splitlines()[0] if str(e) else type(e).__name__
        raise InputError(
            f"--scheduler {address!r}: no Dask scheduler answers there within {timeout:g} s ({why})"
        ) from None
    with client, parallel_config(backend="dask"):
        yield client
