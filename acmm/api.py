"""A small Python API: load a config, design, simulate, linearize — results as python-control
``StateSpace`` objects with named states, inputs and outputs.

>>> import control
>>> from acmm import api
>>> cfg = api.load_config("staircase")
>>> d = api.design(cfg)                        # sector LQR per design point + gain schedule
>>> cl = d.scheduled_closed_loop(tea_pitch_deg=-20.0)
>>> control.step_response(cl, T=20000.0)        # doctest: +SKIP

Conventions (eq 4.46): x = the 24 states of :data:`acmm.model.linearize.STATE_NAMES` (rad, rad/s,
ft·lbf·s, ft·lbf·s², DRF states), control u (ft·lbf) enters ω' as −u and h' as +u, the
disturbance w (ft·lbf) enters ω' as +w; the LQR law is u = −K x.  Every system here is in the
report's (imperial) units whatever ``output.units`` says; time is in s.

Systems: :meth:`Design.open_loop` (inputs u1..u3, w1..w3; outputs the 24 states);
:meth:`Design.closed_loop` (point k with its own LQR gain: x' = (A − B K) x + B v + G w, inputs
v1..v3, a torque added to −K x, and w1..w3, outputs the 24 states and u1..u3);
:meth:`Design.scheduled_closed_loop` (the same at any pitch TEA along the blend, with the scheduled
gain K(θ2*) and the plant linearized at the blended station's own TEA); :meth:`Design.loop_transfer`
(L = K (sI − A)⁻¹ B broken at the plant input, for ``control.disk_margins``; negative feedback).
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

import acmm.io.config
from acmm.io.config import Config
from acmm_qpp.errors import ConfigError
from acmm.model import linearize as lin
from acmm.stages.simulate import run_simulate
from acmm.stages.design import compute_design
from acmm.design import schedule_points as sp
from acmm.model.tea import solve_tea, solve_tea_near
from scipy.optimize import brentq
from acmm.model.linearize import DISTURBANCE_NAMES, INPUT_NAMES

__all__ = ["load_config", "design", "simulate", "linearize", "Design"]

V_NAMES = ["v1", "v2", "v3"]


class UnknownPointError(ConfigError, KeyError, IndexError):
    """A design point that a design does not have (by name or index); also a KeyError and an
    IndexError, as a lookup in a list or mapping of the points would raise."""

    __str__ = Exception.__str__


def load_config(config: str | Path | Config | None = None) -> Config:
    """A validated :class:`acmm.io.config.Config` from a path, a packaged name (``"mb3"``), or
    ``None`` (the packaged stair-case); a ``Config`` is returned as is.

    Parameters
    ----------
    config : str or pathlib.Path or acmm.io.config.Config or None, optional
        Config file, packaged name, a config, or None.

    Returns
    -------
    acmm.io.config.Config
        The validated config.

    Raises
    ------
    ConfigError
        Not a path, name or Config; or the config is invalid.
    """
    if isinstance(config, Config):
        return config
    if config is not None and not isinstance(config, (str, Path)):
        raise ConfigError(f"config must be a path, a packaged config's name or a Config, not {type(config).__name__}")
    return acmm.io.config.load_config(config)


def linearize(config, tea_pitch_deg: float | None = None):
    """The 24-state design model (:class:`acmm.model.linearize.LinearModel`) of a config at its TEA,
    or of its blended station whose pitch TEA is ``tea_pitch_deg``.  ``.to_statespace()`` gives
    the python-control system.

    Parameters
    ----------
    config : str or pathlib.Path or acmm.io.config.Config or None
        The config (see :func:`load_config`).
    tea_pitch_deg : float, optional
        Pitch TEA θ2* of the blended station, deg (default: the config's own TEA).

    Returns
    -------
    acmm.model.linearize.LinearModel
        The design model (eqs 4.46–4.47), in the report's units.
    """
    cfg = load_config(config)
    if tea_pitch_deg is None:
        return lin.linearize_config(cfg)
    return design(cfg, _compute=False).model_at(tea_pitch_deg)


def simulate(config, figures: bool = False):
    """Design (or reuse ``design.h5``), run the nonlinear closed loop and write ``sim.h5``.

    Parameters
    ----------
    config : str or pathlib.Path or acmm.io.config.Config or None
        The config (see :func:`load_config`).
    figures : bool, optional
        Also write the simulation figures.

    Returns
    -------
    tuple
        (:class:`acmm.stages.runners.SimulateResult`, whose ``.sim`` holds t, state, u, verdict;
        pathlib.Path of ``sim.h5``, for ``xarray.open_dataset(path, engine="h5netcdf")``).
    """
    return run_simulate(load_config(config), figures=figures)


def design(config, _compute: bool = True) -> "Design":
    """Design every point of a config (TEA → linearize → sector LQR) and fit its schedule.

    The TEA of eqs 4.1–4.3, the model of eqs 4.46–4.47, the sector LQR of ch. 5.2 and the
    quadratic schedule of ch. 5.3.

    Parameters
    ----------
    config : str or pathlib.Path or acmm.io.config.Config or None
        The config (see :func:`load_config`).
    _compute : bool, optional
        False: no design is computed (``result`` is None), for :func:`linearize` at a blended
        station.

    Returns
    -------
    Design
        The config and its design.
    """
    cfg = load_config(config)
    return Design(cfg, compute_design(cfg) if _compute else None)


def _named(A, B, C, D, states, inputs, outputs, name):
    """A named ``control.StateSpace`` (python-control allows no ``.`` in a name: ``,`` stands for it)."""
    import control  # deferred: python-control start-up (~1.5 s), only for a StateSpace

    return control.ss(A, B, C, D, states=list(states), inputs=list(inputs), outputs=list(outputs),
                      name=name.replace(".", ","))


@dataclass
class Design:
    """A config's design: per-point LQR gains and the gain schedule, as python-control systems.

    Attributes
    ----------
    config : acmm.io.config.Config
        The validated config.
    result : acmm.stages.runners.DesignResult or None
        Its design (per-point models and LQR results, the schedule table); None for
        linearize-only use.
    """

    config: Config
    result: object      # acmm.stages.runners.DesignResult (None for linearize-only use)

    # ------------------------------------------------------------------ design points
    @property
    def points(self) -> list:
        """The design points, in order: each an :class:`acmm.design.schedule.PointDesign` with
        ``spec`` (name, inertia slug·ft², bias ft·lbf, blend parameter s), ``tea`` (θ* in rad),
        ``model`` (the linear model of eq 4.46) and ``gain`` (:class:`acmm.design.methods.PointGain`:
        ``K``, closed-loop ``poles`` in rad/s, sector ``margin`` in units of n, ``energy``, the
        Riccati design and the LMI certificate if any)."""
        return list(self.result.points)

    @property
    def names(self) -> list[str]:
        """Names of the design points, in order."""
        return [p.spec.name for p in self.result.points]

    def _point(self, point):
        """The :class:`acmm.design.schedule.PointDesign` of ``point`` (index or name)."""
        names = self.names
        if isinstance(point, str):
            if point in names:
                return self.result.points[names.index(point)]
        elif isinstance(point, (int, np.integer)) and -len(names) <= int(point) < len(names):
            return self.result.points[int(point)]
        raise UnknownPointError(f"no design point {point!r}: give an index 0…{len(names) - 1} or a name "
                           f"({', '.join(names)})")

    def gain(self, point=0) -> np.ndarray:
        """LQR gain K (3×24, ft·lbf per state unit) of design point ``point`` (index or name).

        Parameters
        ----------
        point : int or str, optional
            Index or name of the design point.

        Returns
        -------
        (3, 24) array
            K of u = −K x, ft·lbf per unit of each state (rad, rad/s, ft·lbf·s, ...).
        """
        return self._point(point).gain.K

    def open_loop(self, point=0):
        """Open-loop design model of a point: inputs u1..u3, w1..w3; outputs the states.

        Parameters
        ----------
        point : int or str, optional
            Index or name of the design point.

        Returns
        -------
        control.StateSpace
            The 24-state model of eq 4.46 (inputs in ft·lbf, time in s).
        """
        return self._point(point).model.to_statespace()

    def closed_loop(self, point=0, outputs=None, inputs=None):
        """Closed loop of a point with its own LQR gain (see the module docstring).

        Parameters
        ----------
        point : int or str, optional
            Index or name of the design point.
        outputs, inputs : list of str, optional
            Only these channels, by name (``["dtheta2"]``, ``["w2"]``): the system keeps its plain
            name, where indexing it (``sys[["dtheta2"], ["w2"]]``) appends python-control's
            ``$indexed``.

        Returns
        -------
        control.StateSpace
            x' = (A − B K) x + B v + G w; inputs v1..v3, w1..w3 (ft·lbf), outputs the 24
            states and u1..u3 (ft·lbf); named ``closed loop at <point>``.
        """
        p = self._point(point)
        return _select(self._closed(p.model, p.gain.K, f"closed loop at {p.spec.name}"), outputs, inputs)

    # ------------------------------------------------------------------ scheduled loop
    def plant_at(self, s: float) -> tuple[np.ndarray, np.ndarray]:
        """(inertia slug·ft², bias ft·lbf) of the blend I(s) = (1−s) I_start + s I_to.

        Parameters
        ----------
        s : float
            Blend parameter, dimensionless (0: first blended point, 1: last).

        Returns
        -------
        tuple
            ((3, 3) array inertia, slug·ft²; (3,) array disturbance bias, ft·lbf).

        Raises
        ------
        ConfigError
            When the config has no blend (``schedule.to``).
        """
        blended = self._blended()
        return _mix(blended[0], blended[-1], s)

    def _blended(self) -> list:
        """The blended design points (:class:`acmm.design.schedule.PointSpec`, at least two)."""
        blended = [p for p in sp.point_specs(self.config) if np.isfinite(p.s)]
        if len(blended) < 2:
            raise ConfigError("the config has no gain schedule (no schedule.to blend): give a config with one")
        return blended

    def _tea_at(self, s: float, guess=None):
        """(inertia slug·ft², TEA) of the blended station at ``s``, the TEA continued from ``guess`` if given."""
        blended = self._blended()
        a, b = blended[0], blended[-1]
        inertia, bias = _mix(a, b, s)
        n = self.config.orbit_rate
        expected = a.expected if s == 0 else b.expected if s == 1 else None   # their bias_from_tea
        t = (solve_tea_near(inertia, n, bias, guess, expected=expected) if guess is not None
             else solve_tea(inertia, n, bias, expected=expected))
        return inertia, t

    def blend_for_tea(self, tea_pitch_deg: float) -> float:
        """Blend parameter s whose station has pitch TEA ``tea_pitch_deg`` (deg), by bisection
        between the design points that bracket it.

        Parameters
        ----------
        tea_pitch_deg : float
            Pitch TEA θ2*, deg.

        Returns
        -------
        float
            Blend parameter s, dimensionless, in [0, 1].

        Raises
        ------
        ConfigError
            No blend in the config, or the pitch TEA is outside the blend's range.
        """
        target = np.radians(tea_pitch_deg)
        grid = np.linspace(0.0, 1.0, max(len(self._blended()), 3))
        teas = [self._tea_at(s)[1].theta for s in grid]
        f = [t[1] - target for t in teas]
        for k in range(len(grid) - 1):
            if f[k] == 0.0:
                return float(grid[k])
            if f[k] * f[k + 1] <= 0.0:
                guess = teas[k]
                return float(brentq(lambda s: self._tea_at(s, guess)[1].theta[1] - target,
                                    grid[k], grid[k + 1], xtol=1e-12))
        lo, hi = np.degrees(min(t[1] for t in teas)), np.degrees(max(t[1] for t in teas))
        raise ConfigError(f"pitch TEA {tea_pitch_deg:g} deg is outside the blend ({lo:.2f} … {hi:.2f} deg)")

    def model_at(self, tea_pitch_deg: float):
        """Design model (:class:`acmm.model.linearize.LinearModel`) of the blended station whose
        pitch TEA is ``tea_pitch_deg``, linearized at its own TEA.

        Parameters
        ----------
        tea_pitch_deg : float
            Pitch TEA θ2*, deg.

        Returns
        -------
        acmm.model.linearize.LinearModel
            The 24-state model of eqs 4.46–4.47 at that station.
        """
        s = self.blend_for_tea(tea_pitch_deg)
        inertia, t = self._tea_at(s)
        d = self.config.design
        return lin.design_point(inertia, t.theta, self.config.orbit_rate, model=d.model, drf_mode=d.drf_mode)

    def scheduled_gain(self, tea_pitch_deg: float) -> np.ndarray:
        """The scheduled gain K(θ2*) (3×24) at pitch TEA ``tea_pitch_deg`` (deg).

        Parameters
        ----------
        tea_pitch_deg : float
            Pitch TEA θ2*, deg.

        Returns
        -------
        (3, 24) array
            K(θ2*) of the quadratic schedule (ch. 5.3), ft·lbf per state unit.
        """
        return self.result.table.gain_at(np.radians(tea_pitch_deg), 0)

    def scheduled_closed_loop(self, tea_pitch_deg: float, outputs=None, inputs=None):
        """Closed loop with the scheduled gain at pitch TEA ``tea_pitch_deg`` (deg): the blended
        station with that TEA, linearized there, under u = −K(θ2*) x + v.

        Parameters
        ----------
        tea_pitch_deg : float
            Pitch TEA θ2*, deg.
        outputs, inputs : list of str, optional
            Only these channels, by name (as in :meth:`closed_loop`).

        Returns
        -------
        control.StateSpace
            Inputs v1..v3, w1..w3 (ft·lbf); outputs the 24 states and u1..u3 (ft·lbf); named
            ``scheduled loop at theta2* -20,00 deg`` (python-control allows no ``.`` in a name).
        """
        name = f"scheduled loop at theta2* {tea_pitch_deg:+.2f} deg"
        return _select(self._closed(*self._scheduled(tea_pitch_deg), name), outputs, inputs)

    def loop_transfer(self, point=0, tea_pitch_deg: float | None = None):
        """Loop transfer L = K (sI − A)⁻¹ B at the plant input (u1..u3 → Ku1..Ku3), for
        ``control.disk_margins(L, omega)``; with ``tea_pitch_deg`` the scheduled loop.

        Parameters
        ----------
        point : int or str, optional
            Index or name of the design point (when ``tea_pitch_deg`` is None).
        tea_pitch_deg : float, optional
            Pitch TEA θ2* of the scheduled loop, deg.

        Returns
        -------
        control.StateSpace
            L from u1..u3 to Ku1..Ku3 (ft·lbf to ft·lbf), time in s.
        """
        if tea_pitch_deg is None:
            p = self._point(point)
            (model, K), where = (p.model, p.gain.K), p.spec.name
        else:
            (model, K), where = self._scheduled(tea_pitch_deg), f"theta2* {tea_pitch_deg:+.2f} deg"
        return _named(model.A, model.B, K, np.zeros((3, 3)), model.state_names, INPUT_NAMES,
                      [f"K{u}" for u in INPUT_NAMES], f"loop transfer at {where}")

    def _scheduled(self, tea_pitch_deg: float):
        """(model of :meth:`model_at`, scheduled gain K(θ2*) at its own pitch TEA) of the blended station."""
        model = self.model_at(tea_pitch_deg)
        return model, self.result.table.gain_at(model.theta_star[1], 0)

    @staticmethod
    def _closed(model, K, name):
        A = model.A - model.B @ K
        B = np.hstack([model.B, model.G])
        C = np.vstack([np.eye(24), -K])
        D = np.vstack([np.zeros((24, 6)), np.hstack([np.eye(3), np.zeros((3, 3))])])
        return _named(A, B, C, D, model.state_names, V_NAMES + DISTURBANCE_NAMES,
                      list(model.state_names) + INPUT_NAMES, name)


def _select(sys, outputs=None, inputs=None):
    """``sys`` restricted to the named ``outputs`` and ``inputs`` (None: all), under its own name."""
    if outputs is None and inputs is None:
        return sys
    sub = sys[list(outputs if outputs is not None else sys.output_labels),
              list(inputs if inputs is not None else sys.input_labels)]
    return _named(sub.A, sub.B, sub.C, sub.D, sub.state_labels, sub.input_labels, sub.output_labels, sys.name)


def _mix(a, b, s: float) -> tuple[np.ndarray, np.ndarray]:
    """(inertia, bias) of the blend (1 − s)·a + s·b of two :class:`acmm.design.schedule.PointSpec`."""
    return (1 - s) * a.inertia + s * b.inertia, (1 - s) * a.bias + s * b.bias
