"""Tabulation and rendering on a Dask cluster (Dask distributed: a scheduler and workers
you already run, dask-jobqueue on HPC, dask-kubernetes in the cloud, or a LocalCluster).

    from bsdflab.distributed import connect
    with connect(cluster="local:2") as client:            # or scheduler="tcp://HOST:8786"
        table = bsdflab.tables.tabulate(model, grid, client=client)
        image = bsdflab.render.render(scene, spp=64, client=client)

The results equal the in-process ones bit for bit: work units are pure functions of the
request's plain dicts, a unit index and the seed, and the driver assembles them in a fixed
order. See docs/distributed.md (starting a cluster, what crosses the wire, the cost model).
"""
from bsdflab.distributed.cluster import connect, local_cluster

__all__ = ["connect", "local_cluster"]
