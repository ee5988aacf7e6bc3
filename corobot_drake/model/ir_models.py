"""Analog output models of the IR distance sensors: what a sensor reports for a true distance.

Two models, by the names a scenario uses (:data:`MODELS`):

``ideal``
    The reading is the distance to the nearest hit, capped at ``maximum_range`` (which is also
    the reading when nothing is hit). This is the original simulation's sensor.

``sharp_gp2d12``
    The output voltage of a Sharp GP2D12-class triangulating IR ranger, quantised by a 10-bit,
    5 V ADC, with seeded Gaussian noise, plus the inverse (voltage -> distance) a robot program
    would use. See :class:`SharpGP2D12`.

Source figures for the GP2D12 (Sharp GP2D12/GP2D15 datasheet, "Electro-optical
Characteristics", Ta = 25 C, Vcc = 5 V, reflector: Kodak R-27 white card, 90 % reflectance):

====================================================  ======  ======  ======
quantity                                              min     typ     max
====================================================  ======  ======  ======
distance measuring range                              10 cm   -       80 cm
output voltage V_O at L = 80 cm                       0.25 V  0.40 V  0.55 V
output change Delta V_O, L = 80 cm -> 10 cm           1.75 V  2.00 V  2.25 V
====================================================  ======  ======  ======

so V_O(10 cm) = 0.40 + 2.00 = 2.40 V typical. The datasheet's figure "analog output voltage vs.
distance to reflective object" shows the output rising as the distance shrinks to a peak of
about 2.5-2.6 V a little under 10 cm, then falling again closer in (the "fold-back": a reading
there is ambiguous with a farther one).

**The model is a curve fit, not the datasheet curve.** In the usable range it is the inverse law
of a triangulating sensor, ``V = A / (d + B)``, through the two typical points
(80 cm, 0.40 V) and (10 cm, 2.40 V): B = 4 cm, A = 33.6 V cm. Its curve points (the tests check
them) are 10 cm 2.400 V, 15 cm 1.768 V, 20 cm 1.400 V, 30 cm 0.988 V, 40 cm 0.764 V,
50 cm 0.622 V, 60 cm 0.525 V, 70 cm 0.454 V, 80 cm 0.400 V. Cross-check: the widely used
linearisation published by Acroname for the GP2D12 ("Linearizing Sharp Ranger Data"),
``d[cm] = 6787 / (ADC - 3) - 4`` for a 10-bit 5 V ADC, i.e. ``V = 33.14 / (d + 4) + 0.015``,
has the same B = 4 cm and stays within 0.02 V of this fit over 10-80 cm.

Below 10 cm the fold-back is a parabola joined to the hyperbola with matching value and slope at
10 cm and peaking at ``peak_voltage`` (2.55 V, read off the datasheet figure): the peak falls at
8.25 cm and the output reaches 0 V near 1 cm (clamped at 0 V closer in). This part is only
qualitative: the datasheet gives no figures there. Beyond 80 cm the hyperbola simply continues
(0.22 V at 1.5 m, 0 V when nothing is hit).

Noise is Gaussian on the voltage (``noise_std``, default 10 mV, about 2 ADC steps), added before
quantisation, from a caller-supplied ``numpy.random.Generator`` seeded from the scenario, so a
run is deterministic. All distances are in metres.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

MODELS = ("ideal", "sharp_gp2d12")
"""The IR output model names a scenario may choose."""


def ideal(distance: np.ndarray | float, maximum_range: float) -> np.ndarray:
    """Ideal reading: the distance, capped at maximum_range (inf, i.e. no hit, reads
    maximum_range)."""
    return np.minimum(np.asarray(distance, dtype=float), maximum_range)


@dataclass(frozen=True)
class SharpGP2D12:
    """A Sharp GP2D12-class analog IR ranger read by an ADC (see the module docstring).

    Defaults are the datasheet's typical figures; every field may be overridden (e.g. from the
    scenario) to model a particular unit.
    """

    a: float = 0.336
    """V m: the inverse law's numerator (33.6 V cm)."""
    b: float = 0.04
    """m: the inverse law's distance offset (4 cm)."""
    min_distance: float = 0.10
    """m: the near end of the usable range; the fold-back joins the inverse law here."""
    max_distance: float = 0.80
    """m: the far end of the usable range."""
    peak_voltage: float = 2.55
    """V: the output's maximum (the top of the fold-back), a little under min_distance."""
    adc_bits: int = 10
    adc_reference: float = 5.0
    """V: ADC full scale."""
    noise_std: float = 0.01
    """V: standard deviation of the Gaussian output noise (0 = noise-free)."""

    def __post_init__(self) -> None:
        if not self.peak_voltage > self._far_law(self.min_distance):
            raise ValueError(
                f"peak_voltage ({self.peak_voltage} V) must exceed the output at min_distance "
                f"({self._far_law(self.min_distance):.3f} V)"
            )
        if not 0.0 < self.min_distance < self.max_distance:
            raise ValueError("need 0 < min_distance < max_distance")
        if self.noise_std < 0.0:
            raise ValueError(f"noise_std must be >= 0, got {self.noise_std}")

    # -- the noise-free curve ---------------------------------------------------------------

    def _far_law(self, d):
        return self.a / (d + self.b)

    @property
    def peak_distance(self) -> float:
        """m: where the fold-back parabola peaks (8.25 cm for the defaults)."""
        v_join = self._far_law(self.min_distance)
        slope = self.a / (self.min_distance + self.b) ** 2  # -dV/dd at the join
        return self.min_distance - 2.0 * (self.peak_voltage - v_join) / slope

    @property
    def _curvature(self) -> float:
        slope = self.a / (self.min_distance + self.b) ** 2
        return slope / (2.0 * (self.min_distance - self.peak_distance))

    def voltage(self, distance: np.ndarray | float) -> np.ndarray:
        """Noise-free, unquantised output voltage at the given distance(s); inf (no hit) -> 0.
        (`voltage_scalar` element by element: one statement of the curve.)"""
        return np.vectorize(self.voltage_scalar, otypes=[float])(distance)

    # -- the ADC ----------------------------------------------------------------------------

    @property
    def adc_step(self) -> float:
        """V per ADC count (4.88 mV for 10 bits at 5 V)."""
        return self.adc_reference / 2**self.adc_bits

    def counts(self, voltage: np.ndarray | float) -> np.ndarray:
        """ADC counts (truncating converter, clamped to 0 .. 2^bits - 1): `counts_scalar`
        element by element."""
        return np.vectorize(self.counts_scalar, otypes=[np.int64])(voltage)

    def quantise(self, voltage: np.ndarray | float) -> np.ndarray:
        """The voltage the ADC reports (counts times the step)."""
        return self.counts(voltage) * self.adc_step

    # -- one reading in plain floats (the curve itself; a sensor's scan calls these) ---------

    def voltage_scalar(self, distance: float) -> float:
        """:meth:`voltage` of one distance, as a float."""
        if distance >= self.min_distance:
            return self.a / (distance + self.b)
        x = distance - self.peak_distance
        near = self.peak_voltage - self._curvature * (x * x)
        return near if near > 0.0 else 0.0

    def counts_scalar(self, voltage: float) -> int:
        """:meth:`counts` of one voltage, as an int."""
        top = 2**self.adc_bits - 1
        x = voltage / self.adc_step
        if x >= top:
            return top
        return math.floor(x) if x > 0.0 else 0

    def distance_from_voltage_scalar(self, voltage: float) -> float:
        """:meth:`distance_from_voltage` of one voltage, as a float."""
        if not voltage > 0.0:
            return self.max_distance
        return min(max(self.a / voltage - self.b, self.min_distance), self.max_distance)

    # -- the sensor -------------------------------------------------------------------------

    def measure(
        self, distance: np.ndarray | float, rng: np.random.Generator | None = None
    ) -> np.ndarray:
        """The ADC's voltage for the true distance(s): curve + noise, quantised.

        rng: the noise source, seeded from the scenario (deterministic runs); None, or
        noise_std == 0, gives the noise-free reading.
        """
        v = self.voltage(distance)
        if rng is not None and self.noise_std > 0.0:
            v = v + rng.normal(0.0, self.noise_std, size=v.shape)
        return self.quantise(v)

    def distance_from_voltage(self, voltage: np.ndarray | float) -> np.ndarray:
        """Distance estimate from a voltage by inverting the inverse law, clamped to the usable
        range [min_distance, max_distance]: a voltage above the 10 cm output (the fold-back
        side is indistinguishable) reads min_distance; one below the 80 cm output (or <= 0)
        reads max_distance. `distance_from_voltage_scalar` element by element."""
        return np.vectorize(self.distance_from_voltage_scalar, otypes=[float])(voltage)


def sharp_gp2d12(
    distance: np.ndarray | float,
    rng: np.random.Generator | None = None,
    sensor: SharpGP2D12 | None = None,
) -> np.ndarray:
    """The ``sharp_gp2d12`` model's reading (ADC voltage) for the true distance(s), with the
    datasheet-typical sensor unless one is given."""
    return (sensor or SharpGP2D12()).measure(distance, rng)
