"""The bumper through the whole station: the Corobot rams the default scene's giant box (2 m,
100 kg) with a front bumper (`bumpers: {front_bumper: {}}`), while a second Corobot stands
beside it on a skid, a bumper under its chassis that the ground alone touches. Then bumpers of
`geometry: link`: two Burgers whose base link (its body box and the caster it stands on) is
the bumper, one driving its body into the box."""

import math

import pytest

from conftest import make_sim
from corobot_drake.config.scenario import load_scenario
from corobot_drake.resources import DEFAULT_SCENARIO
from corobot_drake.robots import robot_spec
from corobot_drake.sensors.bumper import BumperConfig, BumperState

GIANT = load_scenario(DEFAULT_SCENARIO).world.bodies["giant_box"]
BOX_FACE = GIANT.pose.translation[0] + GIANT.shape.size[0] / 2  # m: its near face's x, -0.7366
START = -0.45  # m: the rammer starts facing the box 0.11 m from it, at full speed on arrival
RAM = (f"robots: {{corobot: {{pose: {{translation: [{START}, 0, 0], "
       "rotation: !Rpy {deg: [0, 0, 180]}}, bumpers: {front_bumper: {}}}, "
       "skidder: {pose: {translation: [0, 1.0, 0]}, "
       "bumpers: {skid: {X_PB: {base_frame: chassis, translation: [0, 0, 0.0185]}, "
       "size: [0.06, 0.06, 0.04]}}}}")
"""The skid's box reaches 1.5 mm below the tyres' bottoms: the skidder stands on it."""
DURATION = 0.8  # s: the rammer reaches the box at 0.35 s and is at rest against it by 0.5
MU = 0.5  # the tyres' and the ground's friction (Drake combines two 0.5s as 0.5)
STALL_PUSH = robot_spec("corobot").wheel_radius
"""m: a stalled wheel pushes with its effort limit / this."""


def drive(sim):
    """The rammer at full power for DURATION s: [(t, chassis x, reading) at each physics
    step], the skidder's readings."""
    rammer, skidder = sim.robot("corobot"), sim.robot("skidder")
    rammer.set_power(1.0, 1.0)
    trace, skid = [], []
    while sim.time < DURATION - 1e-9:
        trace.append((sim.time, rammer.pose().x, rammer.reading("front_bumper")))
        skid.append(skidder.reading("skid"))
        sim.advance(0.01)
    return trace, skid


@pytest.fixture(scope="module")
def ram():
    """(sim, *`drive(sim)`)."""
    sim = make_sim(RAM)
    return sim, *drive(sim)


def test_pressed_exactly_while_the_bumper_is_into_the_box(ram):
    _, trace, _ = ram
    config = BumperConfig()
    face = config.X_PB.GetDeterministicValue().translation()[0] + config.size[0] / 2
    contact_x = BOX_FACE + face  # the chassis origin's x when the bumper's face meets the box
    x_at = {round(t, 2): x for t, x, _ in trace}
    # Each sample (every 20 ms) against where the robot was at its time.
    samples = {round(r.time, 2): r for _, _, r in trace}
    assert samples[0.0] == BumperState(False, 0.0, (0.0, 0.0, 0.0), 0.0)
    assert len(samples) == round(DURATION / 0.02)
    assert {t: r.pressed for t, r in samples.items()} == {
        t: bool(x_at[t] < contact_x) for t in samples}
    # It arrived at speed (the first sample past the face is 3.0 mm in, at 0.36 s) and stays.
    first = min(t for t, r in samples.items() if r.pressed)
    assert 0.3 < first < 0.4
    assert all(r.pressed for t, r in samples.items() if t >= first)


def test_the_push_at_rest_is_what_the_tyres_can_give(ram):
    sim, trace, _ = ram
    reading = trace[-1][2]
    rammer = sim.robot("corobot")
    assert abs(rammer.velocity().forward) < 1e-3  # at rest against the box
    # The box pushes the bumper back along its -x, level (the bumper's low friction).
    fx, fy, _ = reading.force_vector
    assert fx == pytest.approx(-reading.force, rel=1e-3)
    assert abs(fy) < 0.01 * reading.force
    # The drive's limit: four stalled motors at their effort limit. At rest the push is what
    # the tyres hand the ground: a stalled wheel its motor's limit, a spinning one mu N (the
    # push lifts the front wheels' load onto the rear ones: the fronts spin). The model's
    # tyres (compliant, rolling on less than their radius; Drake's regularized friction)
    # give 5% less than this rigid-wheel sum (15.0 N of 15.7 N; the limit is 19.9 N).
    effort = sim.scenario.robots["corobot"].contact.effort_limit
    assert reading.force < 4 * effort / STALL_PUSH
    loads = rammer.wheel_loads()
    tyres = sum(min(effort / STALL_PUSH, MU * n) for n in loads.values())
    assert reading.force == pytest.approx(tyres, rel=0.1)


def test_the_ground_never_presses_a_bumper(ram):
    sim, _, skid = ram
    assert all(not r.pressed and r.force == 0.0 for r in skid)
    # Yet the skidder stands on its skid: its wheels carry less than half its weight (the
    # skid, stiffer than the tyres, carries all of it: the wheels read 0 N).
    weight = robot_spec("corobot").mass * 9.81
    assert sum(sim.robot("skidder").wheel_loads().values()) < 0.5 * weight


def test_a_reset_replays_the_readings_bit_for_bit(ram):
    # Its every number is in the Context: the same run again ends where the first did, so the
    # other tests may come before or after this one.
    sim, trace, skid = ram
    sim.reset()
    assert drive(sim) == (trace, skid)


# --- a bumper of `geometry: link`: the link's own collision geometry -----------------------

BURGER_FRONT = 0.037
"""m: the Burger's body box's front face, ahead of its base origin (burger.sdf: a 0.138 m box
at x = -0.032), 4 mm ahead of its tyres: the body is what meets a wall."""
LINK_BUMPER = ("{front: {geometry: link, X_PB: {base_frame: base, "
               f"translation: [{BURGER_FRONT}, 0, 0.082]}}}}}}")
GAP = 0.01  # m: the rammer's body starts this far from the giant box's face
RAM_LINK = f"""
robots:
  rammer:
    robot: burger
    pose: {{translation: [{BOX_FACE + BURGER_FRONT + GAP}, 0, 0],
            rotation: !Rpy {{deg: [0, 0, 180]}}}}
    lidars: {{scan: {{enabled: false}}}}
    bumpers: {LINK_BUMPER}
  still:
    robot: burger
    pose: {{translation: [0, 1.0, 0]}}
    lidars: {{scan: {{enabled: false}}}}
    bumpers: {LINK_BUMPER}
"""
"""Two Burgers whose base link is their bumper (its body box and the caster ball it stands
on): one drives its body into the giant box at half power, the other stands."""
LINK_DURATION = 0.5  # s: the body meets the box between the samples of 0.14 and 0.16 s
SHORT = 0.5e-3
"""m: a sample with the body's front further than this from the box's face is not pressed
(the pose's x alone: the pushing Burger pitches by a fraction of a degree)."""


@pytest.fixture(scope="module")
def link_ram():
    """(sim, {sample time: rammer's base x}, [rammer's readings], [still one's readings])."""
    sim = make_sim(RAM_LINK)
    rammer, still = sim.robot("rammer"), sim.robot("still")
    rammer.set_power(0.5, 0.5)  # at full power its hard shell bounces off: released at times
    x_at, readings, standing = {}, [], []
    while sim.time < LINK_DURATION - 1e-9:
        x_at[round(sim.time, 2)] = rammer.pose().x
        readings.append(rammer.reading("front"))
        standing.append(still.reading("front"))
        sim.advance(0.02)
    return sim, x_at, readings, standing


def test_a_link_bumper_is_the_links_own_geometry(link_ram):
    sim, *_ = link_ram
    plant = sim.station.plant
    base = plant.GetBodyByName("base", plant.GetModelInstanceByName("rammer"))
    inspector = sim.station.scene_graph.model_inspector()
    names = sorted(inspector.GetName(g).split("::")[-1]
                   for g in plant.GetCollisionGeometriesForBody(base))
    assert names == ["body", "caster"]  # the model's: no box added


def test_a_link_bumper_is_pressed_when_its_body_meets_the_box(link_ram):
    _, x_at, readings, _ = link_ram
    samples = {round(r.time, 2): r for r in readings if not math.isnan(r.time)}
    assert len(samples) == round(LINK_DURATION / 0.02) - 1
    # The box's face against the body's front (the rammer faces -x).
    depth = {t: BOX_FACE - (x_at[t] - BURGER_FRONT) for t in samples}
    assert not any(r.pressed for t, r in samples.items() if depth[t] < -SHORT)
    first = min(t for t, r in samples.items() if r.pressed)
    assert first == min(t for t in samples if depth[t] > 0)  # the first sample past the face
    assert 0.1 < first < 0.2
    assert all(r.pressed for t, r in samples.items() if t >= first)  # pushing on, it stays
    # The box pushes the body back: along S's -x (S faces the base's +x, forwards).
    fx, _, _ = samples[max(samples)].force_vector
    assert fx < -0.5 * samples[max(samples)].force


def test_the_ground_never_presses_a_link_bumper_it_stands_on(link_ram):
    sim, _, _, standing = link_ram
    assert all(not r.pressed and r.force == 0.0 for r in standing)
    # Yet the link touches the ground: its caster carries what the wheels do not.
    weight = robot_spec("burger").mass * 9.81
    assert sum(sim.robot("still").wheel_loads().values()) < 0.95 * weight
