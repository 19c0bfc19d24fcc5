"""Tabulation and rendering on a Dask cluster (Dask distributed: a scheduler and workers
you already run, dask-jobqueue on HPC, dask-kubernetes in the cloud, or a LocalCluster).

    from bsdflab.distributed import connect
    with connect(cluster="local:2") as client:            # or scheduler="tcp://HOST:8786"
        table = bsdflab.tables.tabulate(model, grid, client=client)
        image = bsdflab.render.render(scene, spp=64, client=client)

``client=`` is a convenience for ``runner=DaskRunner(client)``: this package registers the
``"dask"`` runner (bsdflab.util.runners), which runs the features' own pure work units
(bsdflab.tables.units, bsdflab.render.units) on the cluster, and the service's executor spec
``dask:<address>`` / ``dask:local:N`` reaches it by that name. The results equal the
in-process ones bit for bit: units are pure functions of the request's plain dicts, a unit
index and the seed, and the driver assembles them in a fixed order. See docs/distributed.md
(starting a cluster, what crosses the wire, the cost model).
"""
from bsdflab.util.extras import require

require("distributed", "dask")  # before the modules that import it: a clear message when missing

from bsdflab.distributed.cluster import connect, local_cluster  # noqa: E402
from bsdflab.distributed.runner import DaskRunner  # noqa: E402

__all__ = ["DaskRunner", "connect", "local_cluster"]
