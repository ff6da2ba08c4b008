"""The sample grid of an expression nonlinearity's sector computation (ch. 10.1, lemma 1).

:class:`SampleGrid` is the part of :class:`qpp.model.nonlin.ExpressionModel` that says *where* φ is
sampled: the parameter samples of Θ, the time grid on [0, t_range], and for each φ channel the
grid of the outputs it depends on (:meth:`SampleGrid.channel_outputs`).  Gridding each channel
over its own outputs rather than over all p keeps a plant whose channels each act on one output
(p decoupled saturations, say) at p one-dimensional grids instead of one p-dimensional one.
"""
from __future__ import annotations

import itertools
import math
from functools import cached_property

import numpy as np


class SampleGrid:
    """Sampling of Y × Θ × [0, t_range] for :class:`qpp.model.nonlin.ExpressionModel` (a mixin: it
    reads the model's ``p``, ``y_range``, ``lo``/``hi``/``nom``, ``names``, ``n_grid``,
    ``n_t``, ``t_range``, ``t``, ``phi`` and ``dep``)."""

    def theta_samples(self) -> np.ndarray:
        """Corners and midpoints of Θ (3^k points, k ≤ 6; else corners and nominal).

        Returns
        -------
        (S, k) ndarray
            The parameter samples, in the config's units.
        """
        return np.array(list(itertools.product(*self._theta_axes())))     # no parameter: one empty row

    def theta_sample_count(self) -> int:
        """The number of rows of :meth:`theta_samples` (counted, not built).

        Returns
        -------
        int
            The number of parameter samples, dimensionless.
        """
        return math.prod(len(a) for a in self._theta_axes())

    def _theta_axes(self) -> list:
        """The values sampled of each parameter: ends, midpoint and nominal (k ≤ 6), else ends."""
        if len(self.names) <= 6:
            return [np.unique([lo, 0.5 * (lo + hi), hi, nm]) for lo, hi, nm in zip(self.lo, self.hi, self.nom)]
        return [np.array([lo, hi]) for lo, hi in zip(self.lo, self.hi)]

    @cached_property
    def diagonal(self) -> np.ndarray:
        """(r,) bool: whether φ_i depends on no output but y_i (its sector is the ratio φ_i / y_i;
        needs r = p), dimensionless."""
        diag = np.array([all(not d for j, d in enumerate(dep) if j != i) for i, dep in enumerate(self.dep)])
        return diag if len(self.phi) == self.p else np.zeros(len(self.phi), bool)

    def channel_outputs(self, i: int) -> list:
        """The outputs (0-based) the sector of φ channel ``i`` is sampled over: those φ_i depends
        on, and y_i itself for a ratio (diagonal) channel.  The other outputs cannot change φ_i,
        so they are held at the low end of their range (a p-dimensional grid for a φ_i of one
        output would grow as (grid points)^p).

        Parameters
        ----------
        i : int
            The φ channel.

        Returns
        -------
        list of int
            Output indices, ascending.
        """
        return [j for j in range(self.p) if self.dep[i][j] or (self.diagonal[i] and j == i)]

    def sector_points(self) -> int:
        """Points at which :attr:`sector_info` samples φ: over the channels, parameter samples ×
        the grid of the channel's outputs (:meth:`channel_outputs`) × times (for a channel that
        depends on t; the others are evaluated once per output point).

        Returns
        -------
        int
            The number of points (counted, not built), dimensionless.
        """
        n_t = self.time_sample_count()
        per_channel = sum(self.sector_grid_size(i) * (n_t if self.t in self.phi[i].free_symbols else 1)
                          for i in range(len(self.phi)))
        return self.theta_sample_count() * per_channel

    def time_sample_count(self) -> int:
        """The number of times at which the sector is sampled (1 when φ does not depend on t).

        Returns
        -------
        int
            The number of time samples, dimensionless.
        """
        return self._t_grid().size

    def sector_grid_size(self, i: int) -> int:
        """Points of φ channel ``i``'s output grid (the mesh of :meth:`channel_outputs`).

        Parameters
        ----------
        i : int
            The φ channel.

        Returns
        -------
        int
            The number of grid points (counted, not built), dimensionless.
        """
        return math.prod(len(a) for a in self._y_grid(self.channel_outputs(i)))

    def _y_grid(self, outputs: list) -> list:
        """The grid axis of each output in ``outputs``, with points near 0 added: ``n_grid``
        points for d ≤ 2 outputs, max(5, ⌊20000^(1/d)⌋) beyond, united with the axis of the grid
        over all p outputs (so never coarser than that one)."""
        def per(d: int) -> int:
            return self.n_grid if d <= 2 else max(5, int(20000 ** (1.0 / d)))

        counts = sorted({per(len(outputs)), per(self.p)})
        axes = []
        for lo, hi in self.y_range[outputs]:
            span = max(hi - lo, 1e-12)
            extra = [x for x in (0.0, 1e-6 * span, -1e-6 * span, 1e-9 * span, -1e-9 * span) if lo <= x <= hi]
            axes.append(np.unique(np.concatenate([*(np.linspace(lo, hi, c) for c in counts), extra])))
        return axes

    def _channel_grid(self, i: int) -> list:
        """Y (p arrays, each (Ny, 1) or (1, 1)) of channel ``i``'s sample grid: the mesh of its
        outputs, every other output at the low end of its range."""
        outs = self.channel_outputs(i)
        mesh = np.meshgrid(*self._y_grid(outs), indexing="ij")
        Y = [np.full((1, 1), lo) for lo in self.y_range[:, 0]]
        for j, m in zip(outs, mesh):
            Y[j] = m.ravel()[:, None]
        return Y

    def _t_grid(self, T=None):
        if not self.t_varies:
            return np.array([0.0])
        return np.linspace(0.0, self.t_range if T is None else T, self.n_t)

    @property
    def t_varies(self) -> bool:
        """Whether φ depends on the time t (else its time grid is t = 0 alone)."""
        return any(self.t in ph.free_symbols for ph in self.phi)
