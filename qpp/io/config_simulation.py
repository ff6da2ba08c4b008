"""The simulation section of a ``qpp`` config: reference signals r_o(t) and r − r_o as sums of
terms, the scenarios (uncertain parameter, disturbance impulse) and the integrator settings of the
nonlinear closed-loop simulations of ch. 13.4 and 14.5.  Re-exported by :mod:`qpp.io.config`.
"""
from __future__ import annotations

from typing import Literal, Optional

from pydantic import Field

from acmm_qpp.results import RUN_NAME_MAX, RUN_NAME_PATTERN
from qpp.io.config_fields import OptSeconds, Radians, RadPerSecond, Seconds, SectionModel


class Term(SectionModel):
    """One additive term of a signal: sin, step (on [t_on, t_off)), or ramp held after t_end."""

    kind: Literal["sin", "step", "ramp"]
    amplitude: float = Field(1.0, description="sin amplitude / step value / ramp slope (per s)")
    omega: RadPerSecond = Field(0.0, ge=0, description="sin frequency, rad/s")
    phase: Radians = Field(0.0, description="sin phase, rad")
    t_on: OptSeconds = Field(None, description="step/ramp start, s (default: −∞ for a step, 0 for a ramp)")
    t_off: OptSeconds = Field(None, description="step end / ramp hold time, s (default: never)")


Signal = list[list[Term]]   # one list of terms per channel


class Scenario(SectionModel):
    """A simulation case: r = r_o + delta_r, uncertain parameter value, disturbance impulse."""

    name: str = Field(pattern=RUN_NAME_PATTERN, max_length=RUN_NAME_MAX)
    delta_r: Optional[Signal] = Field(None, description="reference perturbation r − r_o per channel")
    gamma: float = Field(0.0, description="uncertain parameter: γ (sinusoidal) or payload M in kg (polar_arm)")
    parameters: Optional[dict[str, float]] = Field(None, description="expression kind: parameter values "
                                                                     "(missing ones nominal)")
    impulse_time: OptSeconds = Field(None, ge=0, description="time of a disturbance impulse d = I δ(t − t_i), s")
    impulse: Optional[list[float]] = Field(None, description="impulse size I per disturbance channel (r)")


class Simulation(SectionModel):
    """Nonlinear closed-loop simulation (ch. 13.4 / 14.5)."""

    t_final: Seconds = Field(10.0, ge=1e-9, le=1e5, description="simulated time, s (1 ns … 1e5 s)")
    n_samples: int = Field(2001, strict=True, ge=11, le=200001, description="output samples")
    rtol: float = Field(1e-8, ge=1e-14, lt=1, description="integrator relative tolerance (≥ 1e-14: ~100 ulp)")
    atol: float = Field(1e-10, ge=1e-20, lt=1, description="integrator absolute tolerance")
    r_o: Signal = Field(description="nominal reference r_o(t), one list of terms per output")
    scenarios: list[Scenario] = Field(min_length=1)
