"""The effort-limit pick of `tools/tune_tire_grip.py` (analysis.tire_grip), on made-up rows:
the worst case over every approach and step decides, and the pick is deterministic."""

import pytest

from corobot_drake.analysis import tire_grip

LEFT = "robots.corobot.commands.0.left"


def _box(limit, step, tilt, direction="backwards"):
    return {tire_grip.LIMIT: str(limit), tire_grip.STEP: str(step), "status": "ok",
            "box_approach.direction": direction, "box_approach.angle_deg": "0.0",
            "box_approach.power": "1.0", "corobot.max_tilt_deg": str(tilt)}


def _drive(limit, speed, spin):
    return [{tire_grip.LIMIT: str(limit), LEFT: "1.0", "status": "ok",
             "corobot.steady_speed": str(speed), "corobot.steady_yaw_rate": "0.0"},
            {tire_grip.LIMIT: str(limit), LEFT: "-1.0", "status": "ok",
             "corobot.steady_speed": "0.0", "corobot.steady_yaw_rate": str(spin)}]


def test_the_worst_case_decides_and_ties_go_to_the_smaller_limit():
    # b u / (a^2 + b^2) at 5 rad/s wheels: the figure DRAKE_NOTES quotes (1.61 rad/s).
    assert tire_grip.predicted_spin_rate(5 * 0.060325) == pytest.approx(1.6077, abs=1e-4)
    rows = {"box": [
        _box(0.2, 0.01, 0.9), _box(0.2, 0.005, 1.0),
        _box(0.3, 0.01, 1.3), _box(0.3, 0.005, 1.4, "forwards"),
        _box(0.5, 0.01, 1.3), _box(0.5, 0.005, 1.4),
        _box(1000, 0.01, 12.7), _box(1000, 0.005, 109.2),  # level at 10 ms, flips at 5 ms
    ], "drive": [*_drive(0.2, 0.55, 3.2), *_drive(0.3, 0.6086, 3.22),
                 *_drive(0.5, 0.6086, 3.22), *_drive(1000, 0.6086, 3.22)]}
    table = tire_grip.limits(rows)
    assert [t.effort_limit for t in table] == [0.2, 0.3, 0.5, 1000.0]
    assert table[1].worst_tilt_deg == 1.4 and table[1].worst_case.startswith("5 ms, forwards")
    strongest = table[-1]
    assert tire_grip.verdict(table[0], strongest).startswith("slows the straight drive")
    assert tire_grip.verdict(table[3], strongest).startswith("flips (109 deg: 5 ms")
    picked = tire_grip.pick(table)
    assert picked.effort_limit == 0.3  # 0.3 and 0.5 tie at 1.4 deg: the smaller
    markdown = tire_grip.markdown(table, picked)
    assert "| **0.3 (picked)** | 1.4 | 1.3 | 1.4 |" in markdown
    assert "| unlimited (1000) | 109.2 | 12.7 | 109.2 |" in markdown
