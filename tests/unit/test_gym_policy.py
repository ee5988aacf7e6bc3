"""The gym's policies alone, on made-up observations (no simulation): `DetourPolicy`'s memory
and cost map, and the saved-policy files (`policy.load`)."""

import json
import math

import numpy as np
import pytest

pytest.importorskip("gymnasium")

from corobot_drake.config.sensors import IrSensorConfig
from corobot_drake.gym.detour import (
    CELL,
    CostMap,
    DetourParameters,
    DetourPolicy,
)
from corobot_drake.gym.policy import LinearPolicy, load

CLEAR = [IrSensorConfig().maximum_range] * 12


def observation(goal_distance, goal_bearing=0.0, front=None, speed=0.0, yaw_rate=0.0):
    """A GoToGoal observation (default at rest): the front rays at `front` m (None: nothing
    seen)."""
    rays = list(CLEAR)
    if front is not None:
        rays[:6] = [front] * 6
    return np.array([*rays, goal_distance, goal_bearing, speed, yaw_rate], np.float32)


def test_a_box_seen_ahead_is_avoided_after_it_leaves_the_cone():
    policy = DetourPolicy()
    straight = policy(observation(1.5))
    assert straight[0] == pytest.approx(straight[1]) and straight[0] > 0.5
    left, right = policy(observation(1.5, front=0.4))  # a box on the way
    assert abs(left - right) > 0.5  # turns to go around it
    # The same view with the box out of the cone: still a detour (it remembers the box) ...
    left, right = policy(observation(1.5))
    assert abs(left - right) > 0.5
    # ... which a reset forgets.
    policy.reset()
    left, right = policy(observation(1.5))
    assert left == pytest.approx(right)


def test_the_detour_policy_forgets_by_itself_at_an_episodes_first_observation():
    policy = DetourPolicy()
    policy(observation(1.5, front=0.4))  # a box on the way, at rest: the first observation
    left, right = policy(observation(1.45, speed=0.3, yaw_rate=0.1))  # driving
    assert abs(left - right) > 0.5  # remembers the box
    # At rest after driving: a new episode (a reset leaves the robot still) ...
    left, right = policy(observation(1.45))
    assert left == pytest.approx(right)
    # ... and so is a goal farther than a step's drive from the last one, even moving.
    policy(observation(1.45, front=0.4, speed=0.3))
    left, right = policy(observation(1.2, speed=0.3))
    assert left == pytest.approx(right)


def test_cost_map_goes_around_stored_hits_and_blocks_cells_near_them():
    parameters = DetourParameters()
    grid = CostMap(2.0)
    grid.update(np.zeros((0, 2)), parameters)
    start = np.array([[1.2, 0.0]])
    assert grid.at(start)[0] == pytest.approx(1.2, abs=CELL)  # open field: the distance
    wall = np.column_stack([np.full(30, 0.6), np.linspace(-0.4, 0.4, 30)])
    grid.update(wall, parameters)
    around = grid.at(start)[0]
    # around the wall's ends, at least `clearance` beyond them: longer than the two legs
    leg = math.hypot(0.6, 0.4 + parameters.clearance)
    assert 2 * leg < around < math.inf
    assert np.isinf(grid.at(np.array([[0.6, 0.0], [0.6 + parameters.clearance / 2, 0.0]]))).all()
    assert np.isinf(grid.at(np.array([[5.0, 0.0]])))[0]  # off the map


def test_saved_policies_load_by_kind_and_bad_files_are_named(tmp_path):
    detour = DetourPolicy(DetourParameters(clearance=0.2))
    detour.save(tmp_path / "d.json", note="test")
    assert load(tmp_path / "d.json").parameters == detour.parameters
    linear = LinearPolicy(np.random.default_rng(0).normal(size=(2, 13)))
    linear.save(tmp_path / "l.json")
    np.testing.assert_array_equal(load(tmp_path / "l.json").weights, linear.weights)
    bad = {
        "kind.json": {"kind": "Tabular"},
        "parameters.json": {"kind": "DetourPolicy", "parameters": {"clearance": 0.2}},
        "clearance.json": {"kind": "DetourPolicy", "parameters": {
            **json.loads((tmp_path / "d.json").read_text())["parameters"], "clearance": -1}},
        "weights.json": {"kind": "LinearPolicy", "features": json.loads(
            (tmp_path / "l.json").read_text())["features"], "weights": {"left": [1.0]}},
    }
    for name, data in bad.items():
        (tmp_path / name).write_text(json.dumps(data))
        with pytest.raises(ValueError, match=name.split(".")[0]):
            load(tmp_path / name)
    (tmp_path / "text.json").write_text("not json")
    with pytest.raises(ValueError, match="not a saved policy"):
        load(tmp_path / "text.json")


def test_training_writes_under_out_or_here_and_ships_only_when_asked(tmp_path):
    import importlib.util
    from pathlib import Path

    from corobot_drake.gym.policy import SHIPPED

    tool = Path(__file__).resolve().parents[2] / "tools" / "train_policy.py"
    spec = importlib.util.spec_from_file_location("train_policy", tool)
    train_policy = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(train_policy)
    parse = train_policy._parser().parse_args
    assert train_policy.outputs(parse([])) == (Path("policy.json"),
                                               Path("gym_learning_curve.png"))
    policy, curve = train_policy.outputs(parse(["--out", str(tmp_path / "run")]))
    assert policy.parent == curve.parent == tmp_path / "run"
    policy, curve = train_policy.outputs(parse(["--ship"]))
    assert policy == SHIPPED and curve.parent.name == "images"
