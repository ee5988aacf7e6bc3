"""A robot at rest stays where it stopped (`lab.creep`; docs/physics.md,
"At rest"). Without the drive's hold its wheels roll into a stable facet of the tyres'
hydroelastic mesh; with it they stay."""

import math

import numpy as np
import pytest

from conftest import load_tool
from corobot_drake.model.sdf import WheelContact
from lab import creep

# A quarter facet: the wheels start near the unheld roll's fastest angle (the map in
# docs/physics.md: 1.59 um/s at 1.18 deg), where the hold has the most to hold.
QUARTER_FACET = 0.25 * creep.facet_angle()
SECONDS = 10.0


def test_the_tyre_mesh_has_drakes_76_facets():
    # ceil(2 pi 0.060325 m / 5 mm) = ceil(75.8): Drake's rule for a compliant cylinder.
    assert creep.tyre_facets() == 76
    assert creep.tyre_facets(WheelContact(resolution_hint=0.0025)) == 152
    assert creep.facet_angle() == pytest.approx(math.radians(360 / 76))


def test_unheld_the_wheels_roll_towards_a_stable_facet():
    run = creep.rest_run(QUARTER_FACET, SECONDS, hold=False)
    # Rolling, not slipping: the chassis moves the effective radius (0.0598 m, the tyres
    # sink ~0.5 mm) times the wheels' rotation, within 1%.
    assert run.wheel_rotation > 0  # forward, towards the stable angle at 1.93 deg
    assert run.displacement == pytest.approx(0.0598 * run.wheel_rotation, rel=0.01)
    # 1.59 um/s measured (the same at plant steps 1, 5 and 10 ms to 0.1%); 10% allows a
    # Drake release's change to the mesh's pressure field without hiding a changed cause.
    assert run.rate == pytest.approx(1.59e-6, rel=0.1)


def test_held_a_resting_robot_stays_where_it_stopped():
    run = creep.rest_run(QUARTER_FACET, SECONDS, hold=True)
    # Held, it measures ~1e-11 m in 10 s; unheld 16 um. 0.1 um (10 nm/s, 18 um in 30 minutes
    # were it steady) is 0.6% of the unheld creep: any leak of the hold shows.
    assert run.displacement < 1e-7
    assert abs(run.yaw) < 1e-8  # rad: 2e-11 measured (unheld 1e-8)


def test_predict_integrates_the_rate_map_to_the_stable_angle():
    # A synthetic map over half a facet of 0.1 rad: rolling forward up to 0.03, back after.
    angles = np.linspace(0.0, 0.05, 11)
    rates = 1e-5 * np.sin(2 * np.pi * angles / 0.06) * (angles < 0.05)
    assert creep.stable_angles(angles, rates) == [pytest.approx(0.03, abs=1e-3)]
    # From 0.01 it rolls towards 0.03 and stops there; from 0.02 it gets there sooner.
    assert creep.predict(angles, rates, 0.01, 1e5) == pytest.approx(0.02, abs=1e-4)
    assert 0.0 < creep.predict(angles, rates, 0.01, 100) < 1e-3  # ~1e-5 rad/s x 100 s
    # The mirror half: from 0.09 (0.01 before the next facet) it rolls back to 0.07.
    assert creep.predict(angles, rates, 0.09, 1e5) == pytest.approx(-0.02, abs=1e-4)


def test_a_map_too_coarse_for_the_stable_angle_says_so(capsys):
    # 5 angles 0.59 deg apart step over the roll's turn back (at 1.94 deg, 0.43 deg from
    # half a facet): no stable angle to print, and no distance rolled to it.
    assert load_tool("creep").main(["--points", "5", "--seconds", "0.1", "--minutes", "1"]) == 0
    out = capsys.readouterr().out
    assert "nan" not in out
    assert ("stable wheel angles: none among the 5 mapped angles, 0.59 deg apart (one between "
            "two of them goes unseen: more --points map it finer)") in out
