"""IR output models: the ideal reading and the Sharp GP2D12 curve fit, ADC and noise."""

from __future__ import annotations

import math

import numpy as np
import pytest

from corobot_drake.model.ir_models import MODELS, SharpGP2D12, ideal, sharp_gp2d12

MAXIMUM_RANGE = 0.762

# Datasheet, typical figures (Sharp GP2D12, electro-optical characteristics).
DATASHEET_TYP = [(0.80, 0.40), (0.10, 0.40 + 2.00)]
DATASHEET_MIN_MAX_AT_80CM = (0.25, 0.55)

# The fit's curve points quoted in the module docstring (cm, V).
CURVE_POINTS = [
    (10, 2.400),
    (15, 1.768),
    (20, 1.400),
    (30, 0.988),
    (40, 0.764),
    (50, 0.622),
    (60, 0.525),
    (70, 0.454),
    (80, 0.400),
]


def acroname_voltage(d_m):
    """The Acroname linearisation d[cm] = 6787 / (ADC - 3) - 4 solved for volts (10 bit, 5 V)."""
    return (6787.0 / (d_m * 100.0 + 4.0) + 3.0) * 5.0 / 1024.0


def test_model_names():
    assert MODELS == ("ideal", "sharp_gp2d12")


def test_ideal_caps_at_maximum_range():
    d = np.array([0.0, 0.1, 0.62865, MAXIMUM_RANGE, 0.9, math.inf])
    np.testing.assert_array_equal(
        ideal(d, MAXIMUM_RANGE), [0.0, 0.1, 0.62865, MAXIMUM_RANGE, MAXIMUM_RANGE, MAXIMUM_RANGE]
    )
    assert ideal(math.inf, MAXIMUM_RANGE) == MAXIMUM_RANGE


@pytest.mark.parametrize(("d", "v"), DATASHEET_TYP)
def test_gp2d12_reproduces_the_datasheet_typical_points(d, v):
    assert SharpGP2D12().voltage(d) == pytest.approx(v, abs=1e-12)


@pytest.mark.parametrize(("cm", "v"), CURVE_POINTS)
def test_gp2d12_curve_points(cm, v):
    sensor = SharpGP2D12()
    assert sensor.voltage(cm / 100.0) == pytest.approx(v, abs=5e-4)
    # Within 0.02 V of the independent Acroname linearisation over the usable range.
    assert sensor.voltage(cm / 100.0) == pytest.approx(acroname_voltage(cm / 100.0), abs=0.02)


def test_gp2d12_usable_range_is_monotonic_and_in_the_datasheet_band():
    sensor = SharpGP2D12()
    d = np.linspace(0.10, 0.80, 200)
    v = sensor.voltage(d)
    assert np.all(np.diff(v) < 0)
    lo, hi = DATASHEET_MIN_MAX_AT_80CM
    assert lo <= v[-1] <= hi
    assert 1.75 <= v[0] - v[-1] <= 2.25  # datasheet Delta V_O, 80 -> 10 cm


def test_gp2d12_fold_back():
    sensor = SharpGP2D12()
    d = np.linspace(0.0, 0.10, 1001)
    v = sensor.voltage(d)
    peak = d[np.argmax(v)]
    assert peak == pytest.approx(0.0825, abs=1e-4)
    assert v.max() == pytest.approx(2.55, abs=1e-6)
    assert 2.5 <= v.max() <= 2.6
    # Rises to the peak, folds back below it: a near reading aliases a farther one.
    assert np.all(np.diff(v[d <= peak]) >= 0) and np.all(np.diff(v[d >= peak]) <= 0)
    aliased = sensor.distance_from_voltage(sensor.voltage(0.05))  # 5 cm reads as 12.5 cm
    assert aliased == pytest.approx(0.1253, abs=1e-3)
    assert sensor.voltage(aliased) == pytest.approx(sensor.voltage(0.05), abs=1e-12)
    assert sensor.voltage(0.0) == 0.0
    # Continuous, with a continuous slope, where the fold-back joins the inverse law.
    eps = 1e-7
    v_left, v_join, v_right = sensor.voltage([0.10 - eps, 0.10, 0.10 + eps])
    assert v_left == pytest.approx(v_join, abs=1e-5) and v_right == pytest.approx(v_join, abs=1e-5)
    slope_left = (v_join - v_left) / eps
    slope_right = (v_right - v_join) / eps
    assert slope_left == pytest.approx(slope_right, rel=1e-4)


def test_gp2d12_no_hit_reads_zero_volts():
    assert SharpGP2D12().voltage(math.inf) == 0.0
    assert sharp_gp2d12(math.inf) == 0.0


def test_adc_quantisation():
    sensor = SharpGP2D12()
    step = 5.0 / 1024
    assert sensor.adc_step == step
    d = np.linspace(0.10, 0.80, 500)
    q = sensor.measure(d)  # noise-free
    counts = sensor.counts(sensor.voltage(d))
    np.testing.assert_allclose(q / step, counts, atol=1e-9)  # multiples of one step
    assert np.all((sensor.voltage(d) - q >= 0) & (sensor.voltage(d) - q < step))  # truncation
    assert len(np.unique(q)) < len(d)  # distinct distances share a reading far out
    # 80 cm reads 0.40 V -> count 81 (0.3955 V); full scale is clamped.
    assert sensor.counts(0.40) == 81
    assert sensor.counts(7.0) == 1023 and sensor.counts(-1.0) == 0


def test_noise_is_seeded_and_deterministic():
    sensor = SharpGP2D12()
    d = np.full(1000, 0.30)
    a = sensor.measure(d, np.random.default_rng(1234))
    b = sensor.measure(d, np.random.default_rng(1234))
    c = sensor.measure(d, np.random.default_rng(4321))
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, c)
    assert a.std() == pytest.approx(sensor.noise_std, rel=0.15)
    assert a.mean() == pytest.approx(sensor.voltage(0.30) - sensor.adc_step / 2, abs=0.003)
    quiet = SharpGP2D12(noise_std=0.0)
    np.testing.assert_array_equal(
        quiet.measure(d, np.random.default_rng(1)), quiet.measure(d, None)
    )


def test_inverse_recovers_the_distance_in_the_usable_range():
    sensor = SharpGP2D12()
    d = np.linspace(0.10, 0.80, 71)
    np.testing.assert_allclose(sensor.distance_from_voltage(sensor.voltage(d)), d, atol=1e-12)
    # Through the 10-bit ADC the error grows with distance (the curve flattens): ~1 cm at 80 cm.
    est = sensor.distance_from_voltage(sensor.measure(d))
    err = np.abs(est - d)
    assert err.max() < 0.012
    assert err[d < 0.3].max() < 0.002


def test_inverse_clamps_outside_the_usable_range():
    sensor = SharpGP2D12()
    np.testing.assert_allclose(
        sensor.distance_from_voltage([2.55, 3.0, 0.3, 0.0, -0.1]),
        [0.10, 0.10, 0.80, 0.80, 0.80],
    )


def test_parameters_are_checked():
    with pytest.raises(ValueError, match="peak_voltage"):
        SharpGP2D12(peak_voltage=2.0)
    with pytest.raises(ValueError, match="noise_std"):
        SharpGP2D12(noise_std=-1)


def test_scalar_forms_equal_the_array_forms_exactly():
    """The sensor's scan uses the float forms: they give the array forms' values bit for bit."""
    sensor = SharpGP2D12(noise_std=0.0)
    distances = [*np.linspace(-0.05, 1.5, 3001).tolist(), 0.0, 0.1, 0.0825, 0.8, math.inf]
    for d in distances:
        assert sensor.voltage_scalar(d) == float(sensor.voltage(d)), d
    step = sensor.adc_step
    voltages = [*np.linspace(-1.0, 6.0, 7001).tolist(), 0.0, -0.0, step, 1023 * step,
                1024 * step, 5.0, 1e9]
    for v in voltages:
        counts = sensor.counts_scalar(v)
        assert type(counts) is int and counts == int(sensor.counts(v)), v
        assert sensor.distance_from_voltage_scalar(v) == float(sensor.distance_from_voltage(v)), v
