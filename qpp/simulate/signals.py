"""Reference and disturbance signals of a qpp simulation (CR-185644 ch. 10.2, eqs 10.2, 10.29).

A signal is one list of :class:`~qpp.io.config.Term` (sine, step, ramp) per channel; the reference
r = r_o + Δr of each scenario and the nominal reference r_o (eq 10.29) are evaluated here.
"""
from __future__ import annotations

import numpy as np

from qpp.io.config import Term


def eval_terms(terms: list[Term], t: float) -> float:
    """Value of a sum of :class:`~qpp.io.config.Term` at time t (s).

    Parameters
    ----------
    terms : list of Term
        Sine, step and ramp terms of one channel.
    t : float
        Time, s.

    Returns
    -------
    float
        The sum, in the units of the channel's signal.
    """
    v = 0.0
    for tm in terms:
        if tm.kind == "sin":
            v += tm.amplitude * np.sin(tm.omega * t + tm.phase)
        elif tm.kind == "step":
            on = -np.inf if tm.t_on is None else tm.t_on
            off = np.inf if tm.t_off is None else tm.t_off
            v += tm.amplitude if on <= t < off else 0.0
        else:  # ramp
            on = 0.0 if tm.t_on is None else tm.t_on
            off = np.inf if tm.t_off is None else tm.t_off
            v += tm.amplitude * (min(max(t, on), off) - on)
    return v


def eval_signal(signal, t: float) -> np.ndarray:
    """Vector signal (one list of terms per channel) at time t.

    Parameters
    ----------
    signal : list of list of Term
        One list of terms per channel (empty or None: no channel).
    t : float
        Time, s.

    Returns
    -------
    (p,) ndarray
        The signal's value per channel, in the units of the channels.
    """
    return np.array([eval_terms(ch, t) for ch in signal]) if signal else np.zeros(0)
