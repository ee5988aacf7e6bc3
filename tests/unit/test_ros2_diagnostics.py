"""/diagnostics' statuses from a sample (`ros2.diagnostics.statuses`): their levels."""

from corobot_drake.ros2.diagnostics import ERROR, OK, PAUSED, WARN, statuses


def sample(slip: float, margin: float) -> dict:
    return {"time": 2.0, "robots": {"bot": {
        "stalls": 1, "slip": {"front_left": slip, "front_right": 0.0},
        "tip_margin_deg": margin}}}


def test_statuses_warn_on_new_slips_a_sliding_wheel_and_a_small_tip_margin():
    stats = {"realtime_factor": 0.97, "recent_realtime_factor": 0.95, "slips": 3, "rate": 1.0}
    calm = {s.name: s for s in statuses(stats, sample(0.1, 40.0), slips_before=3)}
    assert [s.level for s in calm.values()] == [OK, OK, OK, OK]
    assert calm["corobot_drake: simulation"].message == "real-time factor 0.95"
    assert calm["corobot_drake: bot drive"].values == {"stalls": 1}
    rough = {s.name: s.level for s in statuses(stats, sample(-0.8, 5.0), slips_before=2)}
    assert rough == {"corobot_drake: simulation": WARN, "corobot_drake: bot drive": OK,
                     "corobot_drake: bot wheel slip": WARN,
                     "corobot_drake: bot tip margin": WARN}
    tipped = statuses(stats, sample(0.0, -1.0), slips_before=3)[-1]
    assert tipped.level == ERROR and tipped.message == "-1.0 deg"


def test_paused_says_so_not_the_factor_of_the_time_before():
    stats = {"realtime_factor": 0.97, "recent_realtime_factor": 0.95, "slips": 4, "rate": 1.0,
             "paused": True}
    simulation = statuses(stats, sample(0.1, 40.0), slips_before=3)[0]
    assert (simulation.level, simulation.message) == (OK, PAUSED)
    assert simulation.message.startswith("paused")
    assert simulation.values == {"paused": True, "rate": 1.0, "slips": 4, "time": 2.0}
