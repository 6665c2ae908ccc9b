"""The transcription's pieces that need no solve: the quintic Hermite interpolant and bad input."""

from __future__ import annotations

import numpy as np
import pytest

from quadruped_dyn.errors import InputError
from quadruped_dyn.experiment.gait import TROT, WALK
from quadruped_dyn.model.robot import Robot
from quadruped_dyn.optimal_control.hermite import interpolate
from quadruped_dyn.optimal_control.transcription import Options, transcribe


def test_quintic_hermite_reproduces_quintics() -> None:
    """Any quintic is its own interpolant: value, rate and acceleration at interior points."""
    rng = np.random.default_rng(0)
    c = rng.normal(size=6)
    h, t0 = 0.07, 0.3
    poly = np.polynomial.Polynomial(c)

    def at(t: float) -> tuple[float, float, float]:
        return float(poly(t)), float(poly.deriv()(t)), float(poly.deriv(2)(t))

    for s in (0.0, 0.25, 0.5, 0.9, 1.0):
        got = interpolate(at(t0), at(t0 + h), s, h)
        assert np.allclose(got, at(t0 + s * h), rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("options, message", [
    (Options(mu=0.0), "mu"),
    (Options(mu=-0.3), "mu"),
    (Options(mu=1e300), "expected 0 < mu <= 1000"),  # was an OverflowError in mu**2
    (Options(nodes_per_phase=2), "expected 3 to 40 collocation nodes per phase"),
    (Options(nodes_per_phase=41), "expected 3 to 40 collocation nodes per phase"),
    (Options(speed=5.0), "beyond"),
    (Options(speed=float("nan")), "beyond"),
    # found by a review: a TypeError from math.isfinite, or a bool, a float count or a
    # collocation point outside its interval taken as given
    (Options(mu="0.6"), r"mu is '0\.6', a str; expected a real number"),
    (Options(speed="0.2"), "speed is '0.2', a str; expected a real number"),
    (Options(fz_min_fraction=None), "f_z minimum fraction is None, a NoneType; expected a real number"),
    (Options(nodes_per_phase=True), "--nodes is True, a bool; expected a whole number"),
    (Options(nodes_per_phase=4.0), "--nodes is 4.0, a float; expected a whole number"),
    (Options(interior_points=(0.5, 1.5)), "expected fractions of an interval, each strictly between 0 and 1"),
    (Options(interior_points=(float("nan"),)), "expected fractions of an interval"),
    (Options(interior_points=0.5), "expected fractions of an interval"),  # type: ignore[arg-type]
])
def test_bad_options_are_input_errors(paper: Robot, options: Options, message: str) -> None:
    with pytest.raises(InputError, match=message):
        transcribe(paper, TROT, options)


def test_walk_has_no_roll_coordinate_constraint(paper: Robot) -> None:
    tr = transcribe(paper, WALK, Options(nodes_per_phase=3))
    assert "roll_moment" not in tr.groups and "com_margin" in tr.groups
