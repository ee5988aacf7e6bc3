"""The HTTP routes, one `APIRouter` per resource; `webapp.create_app` includes them in
`ROUTERS` order (a path's first match wins, so the IR catch-all `/robots/{robot}/{service}`
comes last).
"""

from corobot_drake.serving.routes import camera, directory, drive, sensors, subscriptions

ROUTERS = (directory.router, drive.router, sensors.router, camera.router,
           subscriptions.router, sensors.ir_router)
