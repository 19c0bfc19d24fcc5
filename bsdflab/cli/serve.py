"""`bsdflab serve`: the HTTP API and the lobe-explorer page (uvicorn)."""
from __future__ import annotations

import argparse

from bsdflab.util.extras import require


def register(sub) -> None:
    p = sub.add_parser("serve", help="serve the HTTP API and the lobe explorer page",
                       description="Run the bsdflab service: the HTTP API under /v1 (docs at /docs) and "
                                   "the lobe explorer at /. Jobs (tables, renders) run in worker "
                                   "processes; their state lives in DATA_DIR/jobs.sqlite and their "
                                   "files in DATA_DIR/artefacts. Every option has a BSDFLAB_* "
                                   "environment variable (BSDFLAB_HOST, BSDFLAB_PORT, ...).")
    p.add_argument("--host", default=None, help="address to listen on (default 127.0.0.1)")
    p.add_argument("--port", type=int, default=None, help="port (default 8000; 0 picks a free one)")
    p.add_argument("--data-dir", default=None, help="job store and artefacts (default: the user data folder)")
    p.add_argument("--cache-dir", default=None, help="the table cache, shared with bsdflab tabulate and render "
                                                     "(default: $BSDFLAB_CACHE_DIR or the user cache)")
    p.add_argument("--workers", type=int, default=None,
                   help="job worker processes (default: cores - 1, at most 4)")
    p.add_argument("--log-level", default=None, choices=("critical", "error", "warning", "info", "debug"),
                   help="default $BSDFLAB_LOG_LEVEL or info")
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    uvicorn = require("uvicorn", "service")
    from pydantic import ValidationError

    from bsdflab.service import Settings, create_app
    from bsdflab.service.logs import log_config
    from bsdflab.service.server import bounded_protocol

    overrides = {k: v for k, v in (("host", args.host), ("port", args.port), ("data_dir", args.data_dir),
                                   ("cache_dir", args.cache_dir), ("workers", args.workers),
                                   ("log_level", args.log_level)) if v is not None}
    try:
        settings = Settings(**overrides)
    except ValidationError as e:
        raise ValueError("; ".join(f"{'.'.join(map(str, err['loc']))}: {err['msg']}" for err in e.errors())) from None
    # h11 (its header-size limit holds; httptools accepted 1 MB of headers), with the header
    # deadline, the read timeout and the connection cap of bsdflab.service.server
    config = uvicorn.Config(create_app(settings), host=settings.host, port=settings.port,
                            http=bounded_protocol(settings),
                            log_config=log_config(settings.log_level, settings.log_format == "json"),
                            log_level=settings.log_level, access_log=False, timeout_graceful_shutdown=5,
                            timeout_keep_alive=settings.server_timeout_keep_alive_s,
                            limit_concurrency=None,   # the protocol's cap: /healthz answers beyond it
                            h11_max_incomplete_event_size=settings.server_max_header_bytes,
                            backlog=settings.server_backlog)
    uvicorn.Server(config).run()
    return 0
