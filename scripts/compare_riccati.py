"""Compare the Riccati solvers of acmm.design.riccati on the MB3 and AC design problems.

For each configuration two Riccati equations of the sector LQR (acmm.design.sector_lqr, ch. 5.2) are solved:

* **step 1** — the minimum-energy LQR on A + σn·I (Q = 0, R = I/(100 ft·lbf)²), the solve
  every design starts from;
* **final** — (A + σn·I, B, Q, R) with the Q returned by the design (after pole shifting), the
  equation whose stabilizing solution must reproduce K.

Each is solved by the sign function (eq 5.6 corrected, partial-fraction evaluation), scipy and
Slycot, on the state-scaled problem (x = D x̃, D = diag(LinearModel.scales)) and on the raw
physical-unit problem.  The residual is always evaluated the same way: the relative residual of
acmm.design.riccati.care_residual in the *scaled* coordinates (the unscaled P is mapped by P̃ = DPD).
"!" marks a solution that is not stabilizing; "fail" a solver that returned nothing.  Time is
the median wall time of the solve alone (no verification) over ``--repeat`` runs, with
single-threaded BLAS.

Usage: python scripts/compare_riccati.py [--repeat 7] [--out FILE.md]
"""
from __future__ import annotations

import os

# Time single-threaded BLAS: 24/48-order problems only lose to thread start-up and contention
# (several-fold slower on a loaded 2-core machine).  Must precede the numpy import.
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

from acmm.design.riccati import care_condition, care_residual, scale_problem, solve_unverified  # noqa: E402
from acmm.design.sector_lqr import sector_lqr  # noqa: E402
from acmm.design.settings import design_settings  # noqa: E402
from acmm.io.config import load_config  # noqa: E402
from acmm.model.linearize import linearize_config  # noqa: E402
from acmm.report.numbers import markdown_table  # noqa: E402
from acmm_qpp.errors import ConvergenceError  # noqa: E402

SOLVERS = [("sign", {}), ("sign (polynomial eval.)", {"sign_evaluation": "polynomial"}),
           ("scipy", {}), ("slycot", {})]


def problems(name):
    cfg = load_config(name)
    m = linearize_config(cfg)
    sec = cfg.design.sector
    d = m.scales
    alpha = sec.sigma * m.n
    R = cfg.design.R * np.eye(3)
    q0 = design_settings(cfg).q0_weight(24)                       # on the scaled states
    design = sector_lqr(m.A, m.B, R, m.n, sigma=sec.sigma, half_angle_deg=sec.half_angle_deg,
                        Q0=q0, scale=d, min_margin=cfg.design.min_margin,
                        line_spacing=cfg.design.line_spacing)
    As = m.A + alpha * np.eye(24)
    q0_phys = np.zeros((24, 24)) if q0 is None else q0 / d[:, None] / d[None, :]
    return d, R, {"step 1": (As, m.B, q0_phys), "final": (As, m.B, design.Q)}


def measure(A, B, Q, R, d, scaled, solver, kw, repeat):
    """(scaled relative residual, stabilizing?, median seconds) or None on failure."""
    At, Bt, Qt = scale_problem(A, B, Q, d)
    args = (At, Bt, Qt, R) if scaled else (A, B, Q, R)
    method = solver.split()[0]
    times = []
    try:
        for _ in range(repeat):
            t0 = time.perf_counter()
            P, _it = solve_unverified(*args, method=method, **kw)
            times.append(time.perf_counter() - t0)
    except ConvergenceError:
        return None
    Pt = P if scaled else P * d[:, None] * d[None, :]
    Pt = 0.5 * (Pt + Pt.T)
    res = care_residual(At, Bt, Qt, R, Pt)
    K = np.linalg.solve(R, Bt.T @ Pt)
    stable = bool(np.max(np.linalg.eigvals(At - Bt @ K).real) < 0) and np.all(np.isfinite(Pt))
    return res, stable, float(np.median(times))


def table(repeat=7) -> tuple[str, str]:
    """The Markdown table (residual / time per solver, states and problem), and the line of
    κ_CARE (acmm.design.riccati.care_condition, scaled) of each problem from scipy's solution."""
    cols, data, kappa = [], {}, []
    for name in ("mb3", "ac"):
        d, R, probs = problems(name)
        for pname, (A, B, Q) in probs.items():
            col = f"{name.upper()} {pname}"
            cols.append(col)
            for solver, kw in SOLVERS:
                for scaled in (True, False):
                    data[(solver, scaled, col)] = measure(A, B, Q, R, d, scaled, solver, kw, repeat)
            At, Bt, Qt = scale_problem(A, B, Q, d)
            P, _ = solve_unverified(At, Bt, Qt, R, method="scipy")
            kappa.append(f"{col}: {care_condition(At, Bt, Qt, R, 0.5 * (P + P.T)):.1e}")
    rows = [[solver, "scaled" if scaled else "unscaled"]
            + ["fail" if r is None else f"{r[0]:.1e}{'' if r[1] else ' !'} / {r[2] * 1e3:.1f} ms"
               for r in (data[(solver, scaled, col)] for col in cols)]
            for solver, _kw in SOLVERS for scaled in (True, False)]
    return markdown_table(["solver", "states", *cols], rows), "κ_CARE (scaled): " + "; ".join(kappa)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--out", default=None, help="also write the table to this markdown file")
    a = ap.parse_args()
    t, kappa = table(a.repeat)
    print(t)
    print("\nrelative residual (acmm.design.riccati.care_residual, scaled coordinates) / median solve time;"
          " '!' = not stabilizing, 'fail' = no solution")
    print(kappa)
    if a.out:
        Path(a.out).write_text(t + "\n")


if __name__ == "__main__":
    main()
