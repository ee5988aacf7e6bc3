"""The service directory and the pages: `/`, `/dashboard`, `/services`, `/simulation`,
`/robots`, `/robots/{robot}`."""

from __future__ import annotations

import html

from fastapi import APIRouter, HTTPException, Request
from fastapi.responses import FileResponse, HTMLResponse, RedirectResponse

from corobot_drake.serving import schemas
from corobot_drake.serving.routes.backend import STATIC_DIR, BackendDep, json_response

router = APIRouter()


@router.get("/", include_in_schema=False)
async def root():
    return RedirectResponse("/dashboard")


@router.get("/favicon.ico", include_in_schema=False)
async def favicon():
    """The pages' icon (SVG: every current browser takes one, whatever its path)."""
    return FileResponse(STATIC_DIR / "favicon.svg", media_type="image/svg+xml",
                        headers={"Cache-Control": "max-age=86400"})


@router.get("/dashboard", response_class=HTMLResponse, tags=["pages"],
            summary="The dashboard: drive pad, IR gauges, pose, encoders, camera")
async def dashboard():
    return HTMLResponse((STATIC_DIR / "dashboard.html").read_text())


@router.get("/services", response_model=schemas.Directory, tags=["directory"],
            summary="Every robot's services (JSON; HTML for browsers or with ?format=html)")
async def services(request: Request, backend: BackendDep, format: str | None = None):
    entries = [s for r in backend.robot_names for s in backend.services_of(r)]
    meshcat_url = backend.runner.meshcat_url
    want_html = format == "html" or (
        format is None and "text/html" in request.headers.get("accept", ""))
    if format not in (None, "html", "json"):
        raise HTTPException(422, f"format must be html or json, got {format!r}")
    if want_html:
        return HTMLResponse(directory_html(entries, meshcat_url))
    return json_response({"services": entries, "simulation_url": "/simulation",
                          "dashboard_url": "/dashboard", "meshcat_url": meshcat_url})


@router.get("/simulation", tags=["directory"],
            summary="Simulation time, real-time factor, runner statistics")
async def simulation(backend: BackendDep):
    stats = backend.runner.stats()
    stats["robots"] = backend.robot_names
    stats["meshcat_url"] = backend.runner.meshcat_url
    return json_response(stats)


@router.get("/robots", tags=["directory"], summary="Robot names")
async def robots(backend: BackendDep):
    return json_response({"robots": backend.robot_names})


@router.get("/robots/{robot}", tags=["directory"], summary="One robot's services and state")
async def robot_root(robot: str, backend: BackendDep):
    info = backend.robot(robot)
    return json_response({"robot": robot, "services": backend.services_of(robot),
                          "capabilities": info.capabilities,
                          "state": backend.snapshot_of(robot)})


def directory_html(entries: list[dict], meshcat_url: str | None) -> str:
    """The service directory as an HTML page."""
    rows = []
    for e in entries:
        links = [f'<a href="{html.escape(e["state_url"])}">state</a>']
        if e.get("subscribe_url"):
            links.append(f'<a href="{html.escape(e["subscribe_url"])}">subscribe</a>')
        if e.get("page_url"):
            links.append(f'<a href="{html.escape(e["page_url"])}">page</a>')
        rows.append(
            f"<tr><td>{html.escape(e['robot'])}</td><td>{html.escape(e['name'])}</td>"
            f"<td><code>{html.escape(e['contract'])}</code></td><td>{' | '.join(links)}</td>"
            f"<td>{html.escape(', '.join(e.get('operations', [])))}</td></tr>")
    meshcat = (f' | <a href="{html.escape(meshcat_url)}">Meshcat</a>' if meshcat_url else "")
    return f"""<!doctype html>
<html><head><meta charset="utf-8"><title>Service directory - corobot-drake</title>
<link rel="stylesheet" href="/static/style.css">
<link rel="icon" href="/favicon.ico" type="image/svg+xml"></head>
<body><h1>Service directory</h1>
<p><a href="/dashboard">Dashboard</a> | <a href="/simulation">Simulation</a> |
<a href="/docs">API docs</a> | <a href="/openapi.json">OpenAPI</a>{meshcat}</p>
<table class="directory"><thead><tr><th>robot</th><th>service</th><th>contract</th>
<th>links</th><th>operations</th></tr></thead><tbody>
{''.join(rows)}
</tbody></table></body></html>
"""
