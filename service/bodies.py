"""JSON bodies parsed and validated off the event loop.

FastAPI parses a JSON body (``json.loads``) and validates it (pydantic) on the event loop:
a 4 MiB body of 100 000 direction vectors held it up for about half a second, and
``/healthz`` with it. `ThreadedBody` routes do both on a worker thread and hand FastAPI the
validated model, which it then accepts as is (pydantic does not validate an instance of
the model again). Before parsing, a body of more JSON arrays and objects than
``BSDFLAB_LIMIT_JSON_CONTAINERS`` is refused by counting brackets (the parse itself holds
the GIL). A body that does not validate is answered 422 with the bounded error
list (bsdflab.service.errors.bounded_errors), made on that thread too.
"""
from __future__ import annotations

import json
from typing import Any

from fastapi import HTTPException, Request
from fastapi.routing import APIRoute
from pydantic import BaseModel, ValidationError
from starlette.concurrency import run_in_threadpool

from bsdflab.service.errors import bounded_errors
from bsdflab.service.settings import limit_variable


def _parse(body: bytes, model: type[BaseModel] | None, settings) -> Any:
    _count_containers(body, settings)
    value = json.loads(body)
    if model is None:
        return value
    try:
        return model.model_validate(value)
    except ValidationError as e:
        errors = e.errors(include_url=False)
        # an HTTPException is what FastAPI lets out of its body reading unchanged
        raise HTTPException(422, bounded_errors([{**err, "loc": ("body", *err["loc"])} for err in errors])) from None


def _count_containers(body: bytes, settings) -> None:
    """Refuse, before parsing, a body of more JSON arrays and objects than the limit: they
    are what parsing costs most (``json.loads`` and pydantic hold the GIL throughout, so a
    thread alone does not keep /healthz answering during a 3-second parse). Brackets inside
    strings count too: the cap is conservative."""
    containers = body.count(b"[") + body.count(b"{")
    if containers > settings.limit_json_containers:
        raise HTTPException(422, f"the body has {containers} JSON arrays and objects, more than the limit of "
                                 f"{settings.limit_json_containers} ({limit_variable('limit_json_containers')})")


class _ThreadedJson(Request):
    model: type[BaseModel] | None = None

    async def json(self) -> Any:
        if not hasattr(self, "_json"):
            body = await self.body()
            # counted on the thread too: under the bench's heaviest mix, counting 300 KB bodies took
            # 3.5 % of the event loop's time (py-spy, docs/service.md "Performance")
            self._json = await run_in_threadpool(_parse, body, self.model, self.app.state.settings)
        return self._json


class ThreadedBody(APIRoute):
    """A route whose JSON body is parsed and validated on a thread (``route_class``)."""

    def get_route_handler(self):
        handler = super().get_route_handler()
        field = getattr(self, "body_field", None)
        annotation = getattr(getattr(field, "field_info", None), "annotation", None)
        model = annotation if isinstance(annotation, type) and issubclass(annotation, BaseModel) else None
        request_class = type("ThreadedJson", (_ThreadedJson,), {"model": model})

        async def route(request: Request):
            return await handler(request_class(request.scope, request.receive))

        return route
