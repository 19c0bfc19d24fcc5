"""`--scheduler` / `--cluster`: run a command's work on a Dask cluster (bsdflab.distributed)."""
from __future__ import annotations

import contextlib


def add_cluster_options(p) -> None:
    g = p.add_mutually_exclusive_group()
    g.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="run the work units on the Dask cluster of this scheduler (e.g. tcp://HOST:8786)")
    g.add_argument("--cluster", default=None, metavar="local:N",
                   help="run the work units on a local Dask cluster of N worker processes")


@contextlib.contextmanager
def client_from_args(args):
    """None (this process's threads) or a connected Dask client; an unreachable scheduler
    is a one-line error before any work starts."""
    if args.scheduler is None and args.cluster is None:
        yield None
        return
    from bsdflab.distributed import connect

    with contextlib.ExitStack() as stack:
        try:
            client = stack.enter_context(connect(scheduler=args.scheduler, cluster=args.cluster))
        except ConnectionError as e:
            raise ValueError(str(e)) from None
        yield client
