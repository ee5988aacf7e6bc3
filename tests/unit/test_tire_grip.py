"""The effort-limit pick of `tools/tune_tire_grip.py` (corobot_drake.tuning.tire_grip), on
made-up rows: the worst case over every approach and step decides, then the smallest limit
that can still slip a wheel on level ground."""

import pytest

from corobot_drake.tuning import tire_grip

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


def test_the_worst_case_decides_then_the_smallest_limit_that_can_slip_a_wheel():
    # b u / (a^2 + b^2) at 5 rad/s wheels: the figure DRAKE_NOTES quotes (1.61 rad/s).
    assert tire_grip.predicted_spin_rate(5 * 0.060325) == pytest.approx(1.6077, abs=1e-4)
    rows = {"box": [
        _box(0.2, 0.01, 0.9), _box(0.2, 0.005, 1.0),
        _box(0.3, 0.01, 1.3), _box(0.3, 0.005, 1.4, "forwards"),
        _box(0.5, 0.01, 1.3), _box(0.5, 0.005, 1.4),
        _box(1000, 0.01, 12.7), _box(1000, 0.005, 109.2),  # level at 10 ms, flips at 5 ms
    ], "drive": [*_drive(0.2, 0.6086, 3.22), *_drive(0.3, 0.6086, 3.22),
                 *_drive(0.5, 0.6086, 3.22), *_drive(1000, 0.6086, 3.22)]}
    table = tire_grip.limits(rows)
    assert [t.effort_limit for t in table] == [0.2, 0.3, 0.5, 1000.0]
    assert table[1].worst_tilt_deg == 1.4 and table[1].worst_case.startswith("5 ms, forwards")
    strongest = table[-1]
    # mu (m g / 4) R = 0.5 x (4.03 kg x 9.81 / 4) x 0.060325 m: just under the shipped 0.3.
    assert tire_grip.traction_limit() == pytest.approx(0.298, abs=0.001)
    assert tire_grip.verdict(table[0], strongest).startswith("cannot slip a wheel")
    slow = tire_grip.limits({**rows, "drive": [*_drive(0.2, 0.55, 3.2), *rows["drive"][2:]]})
    assert tire_grip.verdict(slow[0], strongest).startswith("slows the straight drive")
    assert tire_grip.verdict(table[3], strongest).startswith("flips (109 deg: 5 ms")
    picked = tire_grip.pick(table)
    assert picked.effort_limit == 0.3  # 0.3 and 0.5 pass: the smaller
    markdown = tire_grip.markdown(table, picked)
    assert "| **0.3 (picked)** | 1.4 | 1.3 | 1.4 |" in markdown
    assert "| unlimited (1000) | 109.2 | 12.7 | 109.2 |" in markdown
