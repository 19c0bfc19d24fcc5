"""The API documentation pages, Swagger UI at /docs and ReDoc at /redoc, with their scripts
and styles served from the installed ``fastapi-offline`` wheel (MIT; it ships the
swagger-ui-dist and ReDoc bundles): nothing is loaded from a CDN, so the pages work offline
and their versions are pinned by the wheel's."""
from __future__ import annotations

from importlib import resources
from pathlib import Path

from fastapi import APIRouter, HTTPException, Request
from fastapi.openapi.docs import get_redoc_html, get_swagger_ui_html, get_swagger_ui_oauth2_redirect_html
from fastapi.responses import FileResponse, HTMLResponse

router = APIRouter(include_in_schema=False)
FILES = {"swagger-ui-bundle.js": "text/javascript", "swagger-ui.css": "text/css",
         "redoc.standalone.js": "text/javascript", "favicon.png": "image/png"}


def _static(name: str) -> Path:
    path = Path(str(resources.files("fastapi_offline") / "static" / name))
    if not path.is_file():
        raise HTTPException(404, f"{name} is missing from the installed fastapi-offline package")
    return path


@router.get("/docs")
def swagger(request: Request) -> HTMLResponse:
    return get_swagger_ui_html(openapi_url="/openapi.json", title=f"{request.app.title} - Swagger UI",
                               oauth2_redirect_url="/docs/oauth2-redirect",
                               swagger_js_url="/vendor/swagger-ui-bundle.js", swagger_css_url="/vendor/swagger-ui.css",
                               swagger_favicon_url="/vendor/favicon.png")


@router.get("/docs/oauth2-redirect")
def oauth2_redirect() -> HTMLResponse:
    return get_swagger_ui_oauth2_redirect_html()


@router.get("/redoc")
def redoc(request: Request) -> HTMLResponse:
    return get_redoc_html(openapi_url="/openapi.json", title=f"{request.app.title} - ReDoc",
                          redoc_js_url="/vendor/redoc.standalone.js", redoc_favicon_url="/vendor/favicon.png",
                          with_google_fonts=False)


@router.get("/vendor/{name}")
def vendored(name: str) -> FileResponse:
    if name not in FILES:
        raise HTTPException(404, f"no file {name}")
    return FileResponse(_static(name), media_type=FILES[name], headers={"Cache-Control": "public, max-age=86400"})
