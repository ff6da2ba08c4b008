"""Reading a design back from ``design.h5`` (ch. 5.2–5.3 results): the table a simulation needs,
checked against the digest the design stage wrote with it.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

import hashlib
import h5py
from acmm.design.schedule import schedule_gain
import yaml
from acmm.model.unit_systems import FT_LBF_IN_NM
from acmm.io.units import convert_items, state_factors
from acmm_qpp.results import h5_text


_TABLE_KEYS = ("inertia", "bias", "tea", "K")


def table_sha256(names, arrays, coef, level=None) -> str:
    """SHA-256 of a design table as stored in ``design.h5`` (names, then the float64 bytes and
    shapes of inertia, bias, tea, K and the schedule's coefficients, then which rows are levels
    when some are not): written by the design stage, checked before a design is reused.

    Parameters
    ----------
    names : sequence of str
        Design point names.
    arrays : sequence of arrays
        inertia, bias, tea and K as stored (the file's units).
    coef : array or None
        The schedule's coefficients as stored (the file's units), or None.
    level : (P,) array of bool or None
        Which rows are stair-case levels (None, or all True: every row).

    Returns
    -------
    str
        Hex digest.
    """
    h = hashlib.sha256("\x1f".join(names).encode())
    extra = () if level is None or np.all(level) else (np.asarray(level, dtype=float),)
    for a in (*arrays, np.zeros(0) if coef is None else coef, *extra):
        a = np.ascontiguousarray(a, dtype=float)
        h.update(f"|{a.shape}|".encode())
        h.update(a.tobytes())
    return h.hexdigest()


def stored_table_digest(items: dict, system: str) -> str:
    """:func:`table_sha256` of ``items`` as :func:`acmm_qpp.results.write_h5` stores them.

    Parameters
    ----------
    items : dict
        The design's datasets (imperial units), as the design stage writes them.
    system : str
        The unit system they are stored in (``"imperial"`` or ``"SI"``).

    Returns
    -------
    str
        The hex digest of the stored table.
    """
    st = convert_items({k: items[k] for k in _TABLE_KEYS} | {"schedule": items.get("schedule", {})}, system)
    coef = st["schedule"]["coef"].data if "coef" in st["schedule"] else None
    level = np.asarray(items["level"].data, bool) if "level" in items else None
    return table_sha256(list(map(h5_text, np.atleast_1d(items["names"].data))), [st[k].data for k in _TABLE_KEYS], coef, level)


def _check_table(names, inertia, bias, tea, K, coef, stored_digest, level=None) -> None:
    """ValueError unless the arrays of a ``design.h5`` have the shapes of ``len(names)`` points,
    are finite and match the digest written with them (an edited or foreign file is designed
    again rather than simulated: a K of the wrong shape reached the compiled simulator)."""
    P = len(names)
    want = {"inertia": (P, 3, 3), "bias": (P, 3), "tea": (P, 3), "K": (P, 3, 24)}
    for k, a in zip(_TABLE_KEYS, (inertia, bias, tea, K)):
        if a.shape != want[k] or not np.all(np.isfinite(a)):
            raise ValueError(f"design.h5: {k} has shape {a.shape} or non-finite values ({P} points)")
    if coef is not None and (coef.ndim != 3 or coef.shape[1:] != (3, 24) or not np.all(np.isfinite(coef))):
        raise ValueError(f"design.h5: schedule/coef has shape {coef.shape} or non-finite values")
    if level is not None and (level.shape != (P,) or not level.any()):
        raise ValueError(f"design.h5: level has shape {level.shape} or no point is a level")
    if P < 1 or (stored_digest is not None
                 and stored_digest != table_sha256(names, (inertia, bias, tea, K), coef, level)):
        raise ValueError("design.h5: its arrays do not match the digest written with them")


def load_design_table(path: Path) -> DesignTable:
    """Read the arrays a simulation needs back from ``design.h5``.

    Parameters
    ----------
    path : pathlib.Path
        A ``design.h5`` (imperial or SI; SI arrays are converted back).

    Returns
    -------
    DesignTable
        The arrays in the report's units (slug·ft², ft·lbf, rad).

    Raises
    ------
    ValueError
        Arrays of the wrong shape, non-finite, or not those written with the file's
        ``table_sha256`` (:func:`design_for` then designs again).
    """
    with h5py.File(path, "r") as f:
        attrs = {k: h5_text(f.attrs[k]) for k in ("design_hash", "schedule_form", "unit_system", "config",
                                                "table_sha256") if k in f.attrs}
        coef = np.asarray(f["schedule/coef"][()], float) if "schedule" in f else None
        names = list(map(h5_text, np.atleast_1d(f["names"][()])))
        inertia, bias, K, tea = (np.asarray(f[k][()], float) for k in ("inertia", "bias", "K", "tea"))
        level = np.asarray(f["level"][()]).astype(bool) if "level" in f else None
    _check_table(names, inertia, bias, tea, K, coef, attrs.get("table_sha256"), level)
    if attrs.get("unit_system", "imperial") == "SI":      # back to the report's units
        drf_mode = (yaml.safe_load(attrs["config"]).get("design") or {}).get("drf_mode", "attitude_hold")
        f, _ = state_factors(drf_mode, "SI")
        inertia, bias = inertia / FT_LBF_IN_NM, bias / FT_LBF_IN_NM
        K = K * f / FT_LBF_IN_NM
        coef = None if coef is None else coef * f / FT_LBF_IN_NM
    return DesignTable(names, inertia, bias, tea, K, coef, attrs["design_hash"],
                       attrs.get("schedule_form", "polynomial"), level)


@dataclass
class DesignTable:
    """What a simulation needs from a design, as arrays (one row per design point).

    Attributes
    ----------
    names : list of str
        Design point names.
    inertia : (P, 3, 3) array
        Inertia per point, slug·ft².
    bias : (P, 3) array
        Bias torque per point, ft·lbf.
    tea : (P, 3) array
        TEA per point, rad.
    gain : (P, 3, 24) array
        LQR gain K per point (u = −K x), ft·lbf per state unit.
    coef : (order+1, 3, 24) array or None
        Schedule coefficients, lowest power first (units of K per rad^k), or None without a
        schedule.
    design_hash : str
        :func:`design_hash` of the config it was designed from.
    form : str
        Schedule form (:func:`acmm.design.schedule.schedule_gain`), ``"polynomial"`` by default.
    level : (P,) array of bool or None
        Which rows are levels of the stair-case (ch. 6); the others are table nodes the schedule's
        refinement added (``schedule.refine_points``).  None: every row.
    """

    names: list
    inertia: np.ndarray      # (P, 3, 3) slug·ft²
    bias: np.ndarray         # (P, 3) ft·lbf
    tea: np.ndarray          # (P, 3) rad
    gain: np.ndarray         # (P, 3, 24) LQR gains
    coef: np.ndarray | None  # (order+1, 3, 24) schedule coefficients, or None
    design_hash: str
    form: str = "polynomial"
    level: np.ndarray | None = None

    def level_rows(self) -> np.ndarray:
        """The rows that are stair-case levels, in order.

        Returns
        -------
        (L,) int array
            Row indices.
        """
        if self.level is None:
            return np.arange(len(self.names))
        return np.flatnonzero(self.level)

    def gain_at(self, theta2: float, k: int) -> np.ndarray:
        """The schedule at pitch TEA ``theta2`` (rad); without a schedule, point k's LQR gain.

        Parameters
        ----------
        theta2 : float
            Pitch TEA θ2*, rad.
        k : int
            Design point whose LQR gain is used when there is no schedule.

        Returns
        -------
        (3, 24) array
            Gain K(θ2*) of the schedule of ch. 5.3, ft·lbf per state unit.
        """
        if self.coef is None:
            return self.gain[k]
        return schedule_gain(self.form, self.coef, self.tea[:, 1], self.gain, theta2)
