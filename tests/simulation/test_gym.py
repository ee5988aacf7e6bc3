"""The GoToGoal Gymnasium environment: its checker, seeds, held boxes, collisions and stalls,
the camera observation, vectorized and Ray rollouts, and the shipped policy."""

import math

import gymnasium
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import corobot_drake.gym
from corobot_drake.gym import ENV_ID, load_policy
from corobot_drake.gym.env import HOVER, GoToGoalConfig, GoToGoalEnv
from corobot_drake.gym.layout import Layout
from corobot_drake.gym.policy import LinearPolicy
from corobot_drake.gym.rollouts import rollouts, run_episode
from corobot_drake.gym.train import HELD_OUT

PARKED = ((0.0, 50.0, 0.0), (2.0, 50.0, 0.0), (4.0, 50.0, 0.0))
"""The three boxes out of the way."""
OPEN_FIELD = Layout(start=(0.0, 0.0, 0.0), goal=(1.5, 0.0), boxes=PARKED)


@pytest.fixture(scope="module")
def env():
    return GoToGoalEnv()


def test_registered_env_passes_gymnasiums_checker():
    env = gymnasium.make(ENV_ID)
    check_env(env.unwrapped, skip_render_check=True)
    assert env.observation_space.shape == (16,)
    assert env.action_space.dtype == np.float32
    assert env.action_space.shape == (2,)


def _play(env, seed, actions):
    obs, _ = env.reset(seed=seed)
    out = [obs]
    for action in actions:
        obs, reward, terminated, truncated, info = env.step(action)
        out += [obs, reward, terminated, truncated, info]
    return out, env.layout


def test_a_seed_gives_the_same_episode_every_time(env):
    actions = np.random.default_rng(1).uniform(-1, 1, (15, 2)).astype(np.float32)
    first, layout = _play(env, 5, actions)
    _play(env, 6, actions)  # another episode in between: nothing of it must remain
    again, same_layout = _play(env, 5, actions)
    assert layout == same_layout
    for a, b in zip(first, again, strict=True):
        if isinstance(a, np.ndarray):
            np.testing.assert_array_equal(a, b)
        else:
            assert a == b
    _, other_layout = _play(env, 6, actions)
    assert other_layout != layout
    # the observation is measured: the robot moved under random powers
    assert first[-5][12] != first[0][12]


def test_observation_is_the_goal_in_the_robot_frame(env):
    layout = Layout(start=(0.0, 0.0, math.pi / 2), goal=(-1.0, 1.0),
                    boxes=PARKED)
    obs, _ = env.reset(seed=0, options={"layout": layout})
    names = env.observation_names()
    assert obs[names.index("goal_distance")] == pytest.approx(math.sqrt(2), abs=1e-3)
    # facing +y, the goal at (-1, 1) is 45 deg to the left
    assert obs[names.index("goal_bearing")] == pytest.approx(math.pi / 4, abs=1e-3)
    # at the start the rear sensor sees nothing (the giant box is to its right), the front
    # neither: every ray reads the range
    assert np.all(obs[:12] == pytest.approx(0.762, abs=1e-6))


def _box_pose(env, i):
    plant = env.sim.station.plant
    return plant.EvalBodyPoseInWorld(plant.GetMyContextFromRoot(env.sim.context),
                                     env.sim.station.bodies[f"box_{i}"]).translation()


def test_driving_into_a_box_is_a_collision_and_a_stall_and_the_box_stays(env):
    # a box 0.5 m ahead on the way to the goal: full power straight into it
    layout = Layout(start=(0.0, 0.0, 0.0), goal=(1.5, 0.0),
                    boxes=((0.5, 0.0, 0.0), (2.0, 50.0, 0.0), (4.0, 50.0, 0.0)))
    obs, _ = env.reset(seed=0, options={"layout": layout})
    start = _box_pose(env, 0)
    assert start[2] == pytest.approx(0.15 + HOVER)
    infos, rewards, front = [], [], []
    for _ in range(30):
        obs, reward, terminated, truncated, info = env.step(np.array([1.0, 1.0], np.float32))
        infos.append(info)
        rewards.append(reward)
        front.append(obs[:6].min())
    # the front face is 0.35 m ahead of the chassis origin, the sensor 0.108 m ahead of it:
    # it read the box coming (0.242 m at the start, nearer as the robot drove)
    assert min(front) < 0.1
    assert any(i["collided"] for i in infos)
    assert sum(i["stalled"] for i in infos[-10:]) >= 8  # pushing, not moving: stalled
    assert rewards[-1] < -0.5  # time cost + collision + stall, no progress
    assert not terminated and not truncated
    # locked (RigidBody.Lock): the robot's push does not move it at all
    assert np.array_equal(_box_pose(env, 0), start)


def test_boxes_stay_locked_after_a_reset(env):
    # Simulation.reset restores the default Context (unlocked): the env locks them again
    env.reset(seed=1)
    plant = env.sim.station.plant
    plant_context = plant.GetMyContextFromRoot(env.sim.context)
    assert all(body.is_locked(plant_context) for body in env.sim.station.bodies.values())


def test_reaching_the_goal_terminates_with_success(env):
    layout = Layout(start=(0.0, 0.0, 0.0), goal=(0.6, 0.0),
                    boxes=PARKED)
    env.reset(seed=0, options={"layout": layout})
    steps, terminated = 0, False
    while not terminated and steps < 30:
        _, reward, terminated, truncated, info = env.step(np.ones(2, np.float32))
        steps += 1
    assert info["is_success"] and not truncated
    assert info["goal_distance"] < env.config.goal_radius
    # 0.4 m at <= 0.61 m/s after a 0.34 s ramp: 0.8-1.2 s
    assert 8 <= steps <= 12
    assert reward > env.config.success_reward


def test_time_limit_truncates(env):
    env.reset(seed=3)
    for _ in range(59):
        assert not any(env.step(np.zeros(2, np.float32))[2:4])
    _, _, terminated, truncated, info = env.step(np.zeros(2, np.float32))
    assert truncated and not terminated and not info["is_success"]
    assert info["time"] == pytest.approx(env.config.time_limit)


def test_camera_adds_the_image_to_a_dict_observation():
    env = GoToGoalEnv(camera=True)
    obs, _ = env.reset(seed=0, options={"layout": OPEN_FIELD})  # facing +x: nothing ahead
    assert set(obs) == {"state", "image"}
    assert obs["image"].shape == (240, 320, 3) and obs["image"].dtype == np.uint8
    assert env.observation_space.contains(obs)
    obs, *_ = env.step(np.zeros(2, np.float32))
    # a rendered scene: the sky above (blue 0.92 x 255), the ground below (0.4 x 255, lit)
    image = obs["image"].astype(int)
    assert image[:40, :, 2].mean() > 200
    assert image[-40:, :, 2].mean() < 150


def test_async_vector_env_steps_the_same_episodes_as_one_env(env):
    # Spawned, not forked: a fork of this process (threads of Ray, Meshcat, the servers'
    # readers) copies locks other threads hold, and a child waiting on one never answers.
    # "module:id": the spawned child imports the module that registers the id.
    envs = gymnasium.vector.AsyncVectorEnv(
        [lambda: gymnasium.make(f"corobot_drake.gym:{ENV_ID}")] * 2, context="spawn")
    try:
        obs, _ = envs.reset(seed=[11, 12])
        actions = np.array([[0.5, 0.8], [-0.3, 0.6]], np.float32)
        for _ in range(5):
            obs, rewards, *_ = envs.step(actions)
    finally:
        envs.close()
    for i, seed in enumerate((11, 12)):
        env.reset(seed=seed)
        for _ in range(5):
            one, reward, *_ = env.step(actions[i])
        np.testing.assert_array_equal(obs[i], one)
        assert rewards[i] == pytest.approx(reward, abs=1e-6)


def test_rollouts_on_ray_equal_episodes_in_this_process(env, ray_head):
    """On the session's Ray head (conftest's `ray_head`), joined by address for the rollouts
    and left after them."""
    import ray

    policy = load_policy()
    on_ray = rollouts(policy, [HELD_OUT[1]], workers=1, address=ray_head.address,
                      progress=False)
    assert not ray.is_initialized()
    here = [run_episode(env, policy, HELD_OUT[1])]
    assert on_ray == here


def test_shipped_policy_reaches_goals_a_random_policy_does_not(env):
    policy = load_policy()
    action = policy(env.reset(seed=0)[0])
    assert env.action_space.contains(action)
    # three of the held-out seeds it reaches (docs/gym.md: 92 of 100)
    seeds = (HELD_OUT[0], HELD_OUT[1], HELD_OUT[3])
    assert all(run_episode(env, policy, s).success for s in seeds)
    random = run_episode(env, None, seeds[0])
    assert not random.success and random.steps == 60


def test_shipped_policy_goes_round_a_box_the_hand_written_one_runs_into(env):
    # Held-out layouts with a box on the straight way: the goal seeker is still short at the
    # time limit; the shipped policy, remembering the box, arrives 12 and 21 steps early.
    shipped, seeker = load_policy(), LinearPolicy.goal_seeker()
    for seed in (HELD_OUT[6], HELD_OUT[20]):
        assert not run_episode(env, seeker, seed).success
        episode = run_episode(env, shipped, seed)
        assert episode.success and episode.steps < 55


def test_shipped_policy_in_a_plain_gymnasium_loop_plays_as_in_the_projects(env):
    # A user's loop (and SB3's evaluate_policy) never calls policy.reset(): the policy starts
    # afresh by itself. Seed 119 after 118 is one it missed when it remembered 118's boxes.
    wrapped = gymnasium.make(ENV_ID)
    policy = load_policy()
    plain = []
    for seed in (118, 119):
        obs, _ = wrapped.reset(seed=seed)
        steps, done = 0, False
        while not done:
            obs, _, terminated, truncated, info = wrapped.step(policy(obs))
            steps, done = steps + 1, terminated or truncated
        plain.append((info["is_success"], steps, info["goal_distance"]))
    ours = [(e.success, e.steps, e.final_distance)
            for e in (run_episode(env, load_policy(), seed) for seed in (118, 119))]
    assert plain == ours
    assert plain[1][0]


def test_policy_round_trips_through_json(tmp_path):
    policy = LinearPolicy(np.random.default_rng(0).normal(size=(2, 13)))
    policy.save(tmp_path / "p.json", note="test")
    np.testing.assert_array_equal(LinearPolicy.load(tmp_path / "p.json").weights,
                                  policy.weights)
    (tmp_path / "bad.json").write_text('{"features": ["x"], "weights": {}}')
    with pytest.raises(ValueError, match="features"):
        LinearPolicy.load(tmp_path / "bad.json")


def test_the_package_registers_one_env():
    assert corobot_drake.gym.ENV_ID in gymnasium.registry
    # Gymnasium's TimeLimit at the env's own limit: 6 s of 0.1 s steps
    spec = gymnasium.spec(ENV_ID)
    config = GoToGoalConfig()
    assert spec.max_episode_steps == round(config.time_limit / config.control_period) == 60
    assert gymnasium.make(ENV_ID).spec.max_episode_steps == 60


@pytest.mark.parametrize("arguments, message", [
    ({"render_mode": "video"}, r"^render_mode must be None or one of rgb_array, human, got "
                               r"'video'$"),
    ({"boxs": 2}, r"^GoToGoalConfig has no field 'boxs'; fields: .*control_period"),
    ({"config": "fast"}, r"^config: must be a GoToGoalConfig; got 'fast'$"),
])
def test_bad_env_arguments_are_one_line(arguments, message):
    with pytest.raises(ValueError, match=message):
        gymnasium.make(ENV_ID, **arguments)


def test_rgb_array_frames_record_a_video(tmp_path):
    """render_mode="rgb_array": Gymnasium's RecordVideo writes the episode, a frame per step
    (and the reset's), each a picture of the scene as it was then."""
    import imageio.v3 as iio
    from gymnasium.wrappers import RecordVideo

    env = gymnasium.make(ENV_ID, render_mode="rgb_array")
    check_env(env.unwrapped)  # Gymnasium's checks of the render mode too
    env = RecordVideo(env, str(tmp_path), episode_trigger=lambda episode: True,
                      disable_logger=True)
    layout = Layout(start=(0.0, 0.0, 0.0), goal=(0.6, 0.0), boxes=PARKED)
    env.reset(seed=0, options={"layout": layout})
    steps, done = 0, False
    while not done:
        _, _, terminated, truncated, info = env.step(np.ones(2, np.float32))
        done, steps = terminated or truncated, steps + 1
    env.close()
    assert info["is_success"]
    (video,) = tmp_path.glob("*.mp4")
    frames = iio.imread(video, index=None, plugin="FFMPEG")  # imageio-ffmpeg: moviepy's
    assert frames.shape == (steps + 1, 480, 640, 3)
    # The robot drove 0.4 m: the first and last frames differ where it was and is (lossy
    # video: a few grey levels everywhere else)
    changed = np.abs(frames[-1].astype(int) - frames[0].astype(int)).max(axis=2) > 40
    assert 0.002 < changed.mean() < 0.2
    # the goal painted as a red disc of its 0.2 m radius: ~50 px across from 4 m up
    red = (frames[0][:, :, 0].astype(int) - frames[0][:, :, 1]) > 80
    assert 0.003 < red.mean() < 0.015


def test_human_render_mode_shows_the_run_in_meshcat():
    """render_mode="human": the scene in a Meshcat on this machine (loopback), the goal drawn
    at its place, the run paced at real time; `render()` returns nothing."""
    env = gymnasium.make(ENV_ID, render_mode="human")
    env.reset(seed=0, options={"layout": OPEN_FIELD})
    unwrapped = env.unwrapped
    meshcat = unwrapped.sim.station.meshcat
    assert meshcat.web_url().startswith(("http://localhost", "http://127.0.0.1"))
    assert meshcat.HasPath("goal")
    assert unwrapped.sim.simulator.get_target_realtime_rate() == 1.0
    env.step(np.ones(2, np.float32))
    assert env.render() is None
    env.close()


@pytest.mark.parametrize("settings, message", [
    (dict(elite=9, population=8), "CemSettings.elite: must be at most the population (8)"),
    (dict(generations=0), "CemSettings.generations: must be in [1, 1000]; got 0"),
    (dict(start="random"), "CemSettings.start: 'random' is not one of"),
])
def test_training_settings_from_python_are_checked_as_the_tools_flags(settings, message):
    from corobot_drake.gym.train import CemSettings

    with pytest.raises(ValueError) as refused:
        CemSettings(**settings)
    assert str(refused.value).startswith(message)


# --- what the env refuses ---------------------------------------------------------------------

BAD_CONFIGS = [
    (dict(control_period=0), "GoToGoalConfig.control_period: must be in [0.01, 10] s"),
    (dict(time_limit=math.nan), "GoToGoalConfig.time_limit: must be in (0, 86400] s; got nan"),
    (dict(time_limit=math.inf), "GoToGoalConfig.time_limit: must be in (0, 86400] s; got inf"),
    (dict(time_limit=0.05), "GoToGoalConfig.time_limit: must be from one to 1000000 control "
     "periods (0.1 s); got 0.05 s"),
    (dict(boxes=-1), "GoToGoalConfig.boxes: must be in [0, 100]"),
    (dict(boxes=2.5), "GoToGoalConfig.boxes: must be a whole number in [0, 100]"),
    (dict(box_size=10**400), "GoToGoalConfig.box_size: must be in [0.01, 2] m; got inf"),
    (dict(goal_distance=(1.8, 1.0)), "GoToGoalConfig.goal_distance: must be (low, high) with "
     "low <= high"),
    (dict(goal_distance=3.0), "GoToGoalConfig.goal_distance: must be (low, high) in m"),
    (dict(goal_clearance=50.0), "GoToGoalConfig.goal_clearance: must be under 2.337 m"),
    (dict(start_spread=1.0), "GoToGoalConfig.start_spread: must be under 0.530 m"),
    (dict(camera="yes"), "GoToGoalConfig.camera: must be True or False"),
    (dict(speed=1.0), "GoToGoalConfig has no field 'speed'"),
]


@pytest.mark.parametrize("overrides, message", BAD_CONFIGS,
                         ids=[next(iter(o)) + str(i) for i, (o, _) in enumerate(BAD_CONFIGS)])
def test_a_config_out_of_range_is_refused_before_anything_is_built(overrides, message):
    with pytest.raises(ValueError) as refused:
        gymnasium.make(ENV_ID, **overrides)
    assert str(refused.value).startswith(message)
    assert "\n" not in str(refused.value)


def test_a_config_that_is_not_one_is_refused():
    with pytest.raises(ValueError, match="config: must be a GoToGoalConfig; got"):
        GoToGoalEnv({"boxes": 2})


def test_the_goal_clearance_bound_is_where_goals_run_out():
    """Under the bound (less a margin) every seed finds a goal; over it no goal exists, and
    `draw_layout` given such a config unchecked says so instead of drawing forever. With
    `start_spread` 0 the start is the origin, 0.7366 m from the giant box's face: the farthest
    goal at 1.8 m is 2.5366 m from it."""
    import dataclasses as dc

    from corobot_drake.gym.checks import check_config
    from corobot_drake.gym.env import GoToGoalConfig
    from corobot_drake.gym.layout import _giant_box_gap, draw_layout

    config = GoToGoalConfig(start_spread=0.0, goal_clearance=2.3)
    check_config(config)
    for seed in range(5):
        layout = draw_layout(np.random.default_rng(seed), config)
        assert _giant_box_gap(*layout.goal) > 2.3
    too_far = dc.replace(config, goal_clearance=2.54)
    with pytest.raises(ValueError, match=r"goal_clearance: must be under 2\.537 m"):
        check_config(too_far)
    with pytest.raises(ValueError, match=r"no goal 2\.54 m clear of the giant box in 10000 draws"):
        draw_layout(np.random.default_rng(0), too_far)


def test_reset_options_and_actions_are_checked(env):
    env.reset(seed=0)
    bad_options = [
        ("garbage", "reset(options=...): must be a dict or None; got 'garbage'"),
        ({"seed": 3}, "reset(options=...): unknown option 'seed'; the only one is 'layout'"),
        ({"layout": (0, 0, 0)}, "reset(options={'layout': ...}): must be a gym.layout.Layout"),
        ({"layout": Layout((0, 0, 0), (1.5, 0), PARKED[:2])},
         "layout.boxes: must hold the env's 3 boxes (GoToGoalConfig.boxes); got 2"),
        ({"layout": Layout((0, 0, 0), (1.5, 0), (*PARKED, (6.0, 50.0, 0.0)))},
         "layout.boxes: must hold the env's 3 boxes (GoToGoalConfig.boxes); got 4"),
        ({"layout": Layout((0, 0, math.nan), (1.5, 0), PARKED)},
         "layout.start.yaw must be a finite number, got nan"),
        ({"layout": Layout((0, 0, 0), (1e9, 0), PARKED)},
         "layout.goal.x must be a finite number in [-10000, 10000], got 1000000000.0"),
        ({"layout": Layout((0, 0, 0), (1.5, 0), ((0.1, 0.0, 0.0), *PARKED[1:]))},
         "reset: the layout: robots.corobot.pose: robot 'corobot' starts"),
    ]
    for options, message in bad_options:
        with pytest.raises(ValueError) as refused:
            env.reset(seed=0, options=options)
        assert str(refused.value).startswith(message), options
    with pytest.raises(gymnasium.error.ResetNeeded):  # the last reset failed: no episode
        env.step([0.0, 0.0])
    env.reset(options={"layout": OPEN_FIELD})
    for action, message in [([math.nan, 0.0], "action: must be 2 finite numbers"),
                            ([0.1, 0.2, 0.3], "action: must be 2 finite numbers"),
                            ("ab", "action: must be 2 numbers"),
                            ([10**400, 0], "action: must be 2 numbers")]:
        with pytest.raises(ValueError, match=message.replace("(", r"\(")):
            env.step(action)
    assert env.sim.time == env.scenario.simulator_config.start_time  # nothing stepped


def test_a_closed_env_refuses_to_step_or_reset():
    env = GoToGoalEnv(boxes=0)
    env.reset(seed=0)
    env.close()
    env.close()  # idempotent
    for call in (lambda: env.step([0.0, 0.0]), lambda: env.reset(seed=1)):
        with pytest.raises(gymnasium.error.ClosedEnvironmentError, match="env is closed"):
            call()
