"""Every error answer is `{"detail": "<one clear sentence>"}`: FastAPI's validation errors and
Starlette's 404/405 rewritten so (`install`)."""

from __future__ import annotations

import json
from typing import Any

from fastapi import FastAPI, Request
from fastapi.exceptions import RequestValidationError
from starlette.exceptions import HTTPException as StarletteHTTPException

from corobot_drake.serving.routes.backend import json_response


def install(app: FastAPI) -> None:
    """Installs the app's exception handlers."""
    app.add_exception_handler(RequestValidationError, _validation_error)
    app.add_exception_handler(StarletteHTTPException, _http_error)


async def _validation_error(request: Request, exc: RequestValidationError):
    message = describe_errors(exc.errors())
    status = 400 if message.startswith("malformed JSON") else 422
    return json_response({"detail": message}, status)


async def _http_error(request: Request, exc: StarletteHTTPException):
    detail = exc.detail if isinstance(exc.detail, str) else json.dumps(exc.detail)
    if exc.status_code == 404 and detail == "Not Found":
        detail = f"no such resource: {request.url.path} (the service directory is /services)"
    if exc.status_code == 405:
        detail = f"{request.method} is not allowed on {request.url.path}"
    return json_response({"detail": detail}, exc.status_code)


def describe_errors(errors: list[dict]) -> str:
    """Pydantic's validation errors in one sentence naming each field."""
    parts = []
    for e in errors:
        loc = ".".join(str(x) for x in e.get("loc", ()) if x != "body") or "body"
        msg = e.get("msg", "invalid")
        if e.get("type") == "json_invalid":
            return f"malformed JSON: {e.get('ctx', {}).get('error', msg)}"
        if e.get("type") == "missing":
            parts.append(f"{loc}: required")
        elif "input" in e and e.get("type") != "extra_forbidden":
            parts.append(f"{loc}: {msg} (got {_short(e['input'])})")
        elif e.get("type") == "extra_forbidden":
            parts.append(f"{loc}: unknown field")
        else:
            parts.append(f"{loc}: {msg}")
    return "; ".join(parts) or "invalid request"


def _short(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."
