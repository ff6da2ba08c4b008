#!/usr/bin/env python
"""The README's numbers about the packaged configs, computed from a fresh run (issue 30, item 4).

Every figure the README quotes about a packaged config (the claims of ch. 6, the per-level
statistics of the stair-case, the design points' margins and conditioning, the schedule along the
path, the ±30 % Monte Carlo counts and the inertia-scaling margins) sits in a block between

    <!-- generated:NAME -->
    ...
    <!-- /generated:NAME -->

and is written by this script from the stages' results files.  The stages are run into a
temporary results root (never the user's ``runs/``) through the report's own functions
(:mod:`acmm.report.stage_results`, :func:`acmm.report.gather.robustness_result`), figures off.

Numbers are rounded to the digits that mean something (3 significant digits for momenta and
attitude errors, 3 decimals for margins in units of n, 2 significant digits for condition numbers
and robustness radii), so the text does not change between machines.

Usage::

    python scripts/readme_numbers.py            # rewrite the blocks of README.md (make readme)
    python scripts/readme_numbers.py --check    # exit 1 and name the blocks that differ

``tests/test_readme_numbers.py`` computes the same blocks from a fresh run and asserts that the
README holds them.
"""
from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")
os.environ.setdefault("MPLBACKEND", "Agg")

import argparse  # noqa: E402
import math  # noqa: E402
import re  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

REPO = Path(__file__).resolve().parent.parent
README = REPO / "README.md"

#: the blocks this script writes, in README order
BLOCKS = ("claims", "staircase_levels", "design_points", "schedule_path", "sweep_monte_carlo",
          "sweep_diverged", "sweep_margin")

MINUS = "\u2212"
_BLOCK_RE = re.compile(r"<!-- generated:(?P<name>[a-z0-9_]+) -->\n(?P<body>.*?)<!-- /generated:(?P=name) -->",
                       re.S)


# ------------------------------------------------------------------------------ formatting
def sig(x: float, digits: int = 3) -> str:
    """``x`` rounded to ``digits`` significant digits, plain notation, thousands spaced.

    Parameters
    ----------
    x : float
        The number.
    digits : int, optional
        Significant digits.

    Returns
    -------
    str
        E.g. ``sig(3986.2) == "3 990"``, ``sig(0.03812) == "0.0381"``, ``sig(-1.964) == "−1.96"``
        (a Unicode minus).
    """
    x = float(x)
    if x == 0 or not math.isfinite(x):
        return f"{x:g}"
    decimals = digits - 1 - math.floor(math.log10(abs(x)))
    r = round(x, decimals)
    if r != 0 and math.floor(math.log10(abs(r))) != math.floor(math.log10(abs(x))):   # 9.99 → 10.0
        decimals -= 1
        r = round(x, decimals)
    text = f"{abs(r):,.{max(decimals, 0)}f}".replace(",", " ")
    return (MINUS if r < 0 else "") + text


def fixed(x: float, decimals: int = 3, sign: bool = False) -> str:
    """``x`` with ``decimals`` decimals and a Unicode minus (``sign``: also a ``+``).

    Parameters
    ----------
    x : float
        The number.
    decimals : int, optional
        Decimals.
    sign : bool, optional
        Write ``+`` before a positive number.

    Returns
    -------
    str
        E.g. ``fixed(-0.4680) == "−0.468"``.
    """
    text = f"{float(x):{'+' if sign else ''}.{decimals}f}"
    if float(text) == 0:
        text = text.lstrip("+-")
    return text.replace("-", MINUS)


def sci(x: float, digits: int = 2) -> str:
    """``x`` in ``1.7e4`` notation with ``digits`` significant digits.

    Parameters
    ----------
    x : float
        The number.
    digits : int, optional
        Significant digits.

    Returns
    -------
    str
        E.g. ``sci(48396.1) == "4.8e4"``, ``sci(2.43e-6) == "2.4e−6"``.
    """
    mant, exp = f"{float(x):.{digits - 1}e}".split("e")
    return f"{mant.replace('-', MINUS)}e{int(exp)}".replace("e-", "e" + MINUS)


def table(header: list[str], rows: list[list[str]], align: str | None = None) -> str:
    """A Markdown table.

    Parameters
    ----------
    header : list of str
        Column titles.
    rows : list of list of str
        Cells.
    align : str, optional
        One character per column, ``l`` or ``r`` (default: all left).

    Returns
    -------
    str
        The table, one line per row, ending with a newline.
    """
    align = align or "l" * len(header)
    rule = ["---" if a == "l" else "--:" for a in align]
    lines = ["| " + " | ".join(r) + " |" for r in [header, rule] + rows]
    return "\n".join(lines) + "\n"


def _text(x) -> str:
    return x.decode() if isinstance(x, bytes) else str(x)


# ------------------------------------------------------------------------------ runs
def use_this_trees_configs() -> None:
    """Make the packaged configs (``acmm.configs``) this tree's ``configs/`` folder.

    An editable install made from another checkout maps ``acmm.configs`` to that checkout's
    folder, whatever ``PYTHONPATH`` says; the README describes this tree's configs.
    """
    import importlib.util

    here = (REPO / "configs").resolve()
    mod = sys.modules.get("acmm.configs")
    if mod is not None and [Path(p).resolve() for p in mod.__path__] == [here]:
        return
    spec = importlib.util.spec_from_file_location("acmm.configs", here / "__init__.py",
                                                  submodule_search_locations=[str(here)])
    mod = importlib.util.module_from_spec(spec)
    sys.modules["acmm.configs"] = mod
    spec.loader.exec_module(mod)


def run_stages(root: Path, workers: int | None = None) -> dict:
    """Run the stages the README quotes into ``root`` and read their results back.

    Parameters
    ----------
    root : pathlib.Path
        Results root (``<root>/<name>/``): an empty temporary folder.
    workers : int, optional
        Worker processes of the sweep (default: min(2, CPUs)).

    Returns
    -------
    dict
        ``"design:<name>"`` (mb3, mb3_decoupled, ac, staircase), ``"simulate:<name>"`` (mb3,
        mb3_decoupled, staircase), ``"sweep"`` (``sweep_inertia30``) → the file as read by
        :func:`acmm_qpp.results.read_h5`; ``"config:<name>"`` → the acmm config.
    """
    from acmm_qpp.errors import AcmmError
    from acmm_qpp.results import read_h5
    from acmm.report.gather import robustness_result
    from acmm.report.stage_results import acmm_config, ensure_acmm_design, ensure_acmm_simulation

    use_this_trees_configs()
    out: dict = {}
    for name in ("mb3", "mb3_decoupled", "ac", "staircase"):
        cfg = acmm_config(name, root)
        out[f"config:{name}"] = cfg
        out[f"design:{name}"] = read_h5(ensure_acmm_design(cfg).path)
        if name != "ac":
            out[f"simulate:{name}"] = read_h5(ensure_acmm_simulation(cfg).path)
    res, note = robustness_result(root, workers=workers)
    if res is None:
        raise AcmmError(f"the sweep for the README did not run: {note}")
    out["sweep"] = res["data"]
    return out


# ------------------------------------------------------------------------------ blocks
def block_claims(r: dict) -> str:
    """Claims 1 and 2 of ch. 6, the sector designs, the schedule along the path, the ±30 % sweep.

    Parameters
    ----------
    r : dict
        :func:`run_stages`.

    Returns
    -------
    str
        A Markdown table.
    """
    n = r["config:mb3"].orbit_rate
    s_c, s_d = r["simulate:mb3"], r["simulate:mb3_decoupled"]
    o, err = s_c["orbits"], np.degrees(np.abs(s_c["attitude_error"]))
    first, late = err[o <= 1.0].max(axis=0), err[o >= 2.0].max(axis=0)
    rows = [
        ["1", "cross-inertia-free MB3 design (`mb3_decoupled`) on the nonlinear model",
         f"{_text(s_d['attrs']['verdict'])} at **{sig(s_d['attrs']['stop_time_orbits'], 2)} orbit**"],
        ["1", "fully coupled MB3 design (`mb3`)",
         f"{_text(s_c['attrs']['verdict'])} over {sig(o[-1], 2)} orbits"],
        ["1", "its peak attitude error in the first orbit, roll / pitch / yaw",
         " / ".join(sig(v) for v in first) + "°"],
        ["1", "its peak attitude error after orbit 2, roll / pitch / yaw",
         " / ".join(sig(v) for v in late) + "°"],
    ]
    st, cfg = r["simulate:staircase"], r["config:staircase"]
    lv = st["levels"]
    orbit = 2 * np.pi / cfg.orbit_rate
    dwell = np.diff(np.append(lv["start"], st["t"][-1])) / orbit
    pitch = np.degrees(lv["tea_estimate"][:, 1])
    steady = np.degrees(lv["steady_error"]).max(axis=0)
    pk = np.asarray(lv["peak_momentum"])
    rows += [
        ["2", f"stair-case MB3 → AC (`staircase`): {len(pk)} levels, pitch TEA "
              f"{sig(pitch[0])}° … {sig(pitch[-1], 2)}°, dwell {sig(dwell.mean())} orbits",
         f"{_text(st['attrs']['verdict'])} over {sig(st['orbits'][-1])} orbits"],
        ["2", "largest steady attitude error of a level, roll / pitch / yaw",
         " / ".join(sig(v, 2) for v in steady) + "°"],
        ["2", "peak CMG momentum per level (every integrator step)",
         f"{sig(pk.min())} … {sig(pk.max())} ft·lbf·s (AC level {sig(pk[-1])}; "
         f"limit {sig(cfg.actuators.momentum_limit)})"],
    ]
    d = r["design:staircase"]
    pa = d["schedule"]["path"]
    mr, mg, dm = (np.asarray(pa[k]) for k in ("max_real", "sector_margin", "disk_margin"))
    margins = [float(np.min(r[f"design:{k}"]["sector_margin"])) for k in ("mb3", "ac", "staircase")]
    conds = [float(np.max(r[f"design:{k}"]["max_eig_condition"])) for k in ("mb3", "ac", "staircase")]
    rows += [
        ["sector", "smallest sector margin of the MB3, AC and 12 stair-case design points",
         f"{fixed(min(margins))}n"],
        ["sector", "relative Riccati residual of those designs (scaled), decade above the largest",
         "≤ " + sci(10.0 ** math.ceil(math.log10(max(float(p["riccati_residual"]) for k in ("mb3", "ac", "staircase")
                                                      for p in r[f"design:{k}"]["points"].values()))), 1)],
        ["sector", "largest eigenvalue condition of A − BK (scaled): AC / MB3 / any stair-case point",
         f"{sci(conds[1])} / {sci(conds[0])} / {sci(conds[2])}"],
        ["schedule", f"largest Re λ of the scheduled loop over {mr.size} path TEAs", f"**{fixed(mr.max())}n**"],
        ["schedule", "worst sector margin along the path", f"{fixed(mg.min(), 2)}n"],
        ["schedule", "smallest disk margin α at the plant input", fixed(dm.min())],
    ]
    w = r["sweep"]
    names = [_text(x) for x in np.atleast_1d(w["base_names"])]
    verdict = np.array([_text(x) for x in np.atleast_1d(w["verdict"])])
    base = np.atleast_1d(w["base"])
    counts = []
    for k, lab in enumerate(names):
        v = verdict[base == k]
        counts.append(f"{lab.upper()} **{int(np.sum(v == 'bounded'))}/{v.size}**")
    rows.append(["ch. 7", "±30 % inertia element draws bounded with the fixed nominal gain "
                          "(`sweep_inertia30`)", ", ".join(counts)])
    return table(["claim", "quantity", "computed"], rows)


def block_staircase_levels(r: dict) -> str:
    """Per-level statistics of the 130-orbit stair-case (``sim.h5: levels/*``).

    Parameters
    ----------
    r : dict
        :func:`run_stages`.

    Returns
    -------
    str
        A Markdown table, one row per level.
    """
    st, cfg = r["simulate:staircase"], r["config:staircase"]
    lv = st["levels"]
    orbit = 2 * np.pi / cfg.orbit_rate
    rows = []
    for k in range(len(lv["start"])):
        rows.append([str(k), sig(lv["start"][k] / orbit), fixed(np.degrees(lv["tea_estimate"][k, 1]), 1),
                     " / ".join(sig(v, 2) for v in np.degrees(lv["steady_error"][k])),
                     sig(lv["peak_momentum"][k])])
    return table(["level", "start (orbit)", "θ2* (deg)", "steady \\|θ − θ̂*\\| roll / pitch / yaw (deg)",
                  "peak \\|h\\| (ft·lbf·s)"], rows, "rrrrr")


def block_design_points(r: dict) -> str:
    """Per design point of the stair-case: sector margin, conditioning, robustness radius.

    Parameters
    ----------
    r : dict
        :func:`run_stages`.

    Returns
    -------
    str
        A Markdown table, one row per design point.
    """
    d = r["design:staircase"]
    rows = []
    for k, name in enumerate(d["names"]):
        rows.append([_text(name), fixed(np.degrees(d["tea"][k, 1]), 1), fixed(d["sector_margin"][k]),
                     sci(d["max_eig_condition"][k]), sci(d["robustness_radius"][k]),
                     sci(d["robustness_radius_elementwise"][k]), sci(d["riccati_condition"][k])])
    return table(["point", "θ2* (deg)", "sector margin (n)", "eigenvalue condition (scaled)",
                  "robustness radius ‖δK̃‖/‖K̃‖", "same, max \\|δK_ij/K_ij\\|", "κ_CARE"], rows, "lrrrrrr")


def block_schedule_path(r: dict) -> str:
    """The scheduled gain on the local loop along the path (``design.h5: schedule/path/*``).

    Parameters
    ----------
    r : dict
        :func:`run_stages`.

    Returns
    -------
    str
        A Markdown table.
    """
    d = r["design:staircase"]
    sc, pa = d["schedule"], d["schedule"]["path"]
    th = np.degrees(np.asarray(pa["theta2"]))
    mr, mg, dm = (np.asarray(pa[k]) for k in ("max_real", "sector_margin", "disk_margin"))
    i = int(np.argmin(dm))
    form = _text(d["attrs"]["schedule_form"]) if "attrs" in d and "schedule_form" in d["attrs"] else (
        "polynomial" if "refit_iterations" in sc else "table")
    rows = [["schedule form", "table look-up, K linear in θ2* between the design points" if form == "table"
             else "2nd-order polynomial in θ2*"]]
    if "refit_iterations" in sc:
        rows += [
            ["least-squares fit before the refit: largest Re λ over the refit's "
             f"{int(sc['refit_n_tea'])} TEAs", f"{fixed(sc['refit_max_real_before'], 2, sign=True)}n"],
            ["closed-loop refit (SLSQP iterations to convergence)", str(int(sc["refit_iterations"]))]]
    rows += [
        ["largest Re λ of the scheduled local loop", f"**{fixed(mr.max())}n**"],
        ["worst sector margin", f"{fixed(mg.min(), 2)}n"],
        ["fraction of the path with every pole in the sector", fixed(np.mean(mg >= 0))],
        ["smallest disk margin α at the plant input (skew 0)",
         f"{fixed(dm[i])} at θ2* = {fixed(th[i], 1)}° (±{sig(pa['disk_gain_margin'][i], 2)} dB, "
         f"±{sig(np.degrees(pa['disk_phase_margin'][i]), 2)}°)"],
    ]
    if "refit_iterations" in sc:
        rows.append(["largest RMS deviation of a refined polynomial from the LQR gains, / max\\|K_ij\\| "
                     "(`schedule/rel_residual`)", sig(np.max(sc["rel_residual"]), 2)])
    return table([f"along the path ({th.size} TEAs, {fixed(th[0], 1)}° … {fixed(th[-1], 1)}°)", "value"], rows)


def block_sweep_monte_carlo(r: dict) -> str:
    """Verdict counts of the ±30 % inertia Monte Carlo (``sweep_inertia30``, ``sweep.h5``).

    Parameters
    ----------
    r : dict
        :func:`run_stages`.

    Returns
    -------
    str
        A Markdown table, one row per base.
    """
    w = r["sweep"]
    names = [_text(x) for x in np.atleast_1d(w["base_names"])]
    verdict = np.array([_text(x) for x in np.atleast_1d(w["verdict"])])
    base, draws = np.atleast_1d(w["base"]), np.atleast_1d(w["n_draws"])
    peak = np.degrees(np.atleast_2d(w["peak_attitude_error"]))
    rows = []
    for k, lab in enumerate(names):
        sel = base == k
        v = verdict[sel]
        nd = int(draws[sel].sum())
        ok = peak[sel][v == "bounded"]
        med = " / ".join(sig(x, 2) for x in np.median(ok, axis=0)) if ok.size else "—"
        rows.append([lab.upper(), str(v.size), f"**{int(np.sum(v == 'bounded'))}**",
                     str(int(np.sum(v == "not_settled"))), str(int(np.sum(v == "diverged"))),
                     str(int(np.sum(v == "no_equilibrium"))),
                     f"{nd - v.size} ({100 * v.size / nd:.0f} % of draws physical)", med])
    return table(["base", "cases", "bounded", "not settled", "diverged", "no equilibrium",
                  "unphysical draws redrawn", "median peak error of the bounded, r / p / y (deg)"],
                 rows, "lrrrrrrr")


def block_sweep_diverged(r: dict) -> str:
    """Where the diverged cases' plants have their equilibrium (``sweep.h5: tea_true``,
    ``tea_estimate``).

    Parameters
    ----------
    r : dict
        :func:`run_stages`.

    Returns
    -------
    str
        A Markdown table, one row per base.
    """
    w = r["sweep"]
    verdict = np.array([_text(x) for x in np.atleast_1d(w["verdict"])])
    base = np.atleast_1d(w["base"])
    rows = []
    for k, lab in enumerate(_text(x) for x in np.atleast_1d(w["base_names"])):
        sel = (base == k) & (verdict == "diverged")
        true = np.degrees(np.atleast_2d(w["tea_true"])[sel, 1])
        est = np.degrees(np.atleast_2d(w["tea_estimate"])[sel, 1])
        lo, hi = np.percentile(true, [5, 95])
        rows.append([lab.upper(), str(int(sel.sum())), f"{sig(lo, 2)}° … {sig(hi, 2)}°",
                     f"{sig(np.median(np.abs(true - est)), 2)}°",
                     f"{sig(np.min(np.atleast_1d(w['time_to_divergence'])[sel]), 2)}"])
    return table(["base", "diverged", "plant's pitch TEA (5–95 %)", "median \\|TEA − estimate\\| (pitch)",
                  "earliest divergence (orbit)"], rows, "lrrrr")


def block_sweep_margin(r: dict) -> str:
    """The tolerated uniform inertia scaling of each fixed design (``sweep.h5: margin/*``).

    Parameters
    ----------
    r : dict
        :func:`run_stages`.

    Returns
    -------
    str
        A Markdown table, one row per base.
    """
    w = r["sweep"]
    mg = w["margin"]
    rows = []
    for lab in (_text(x) for x in np.atleast_1d(w["base_names"])):
        lo, hi = mg[f"{lab}_down"], mg[f"{lab}_up"]
        why = {"bounded": "not settled", "attitude": "diverged"}

        def reason(m):
            text = _text(m["failure_reason"])
            return next((v for k, v in why.items() if text.startswith(k)), text)
        rows.append([lab.upper(), f"{fixed(lo['limit'])} … {fixed(hi['limit'])}",
                     f"{fixed(lo['first_failure'])} ({reason(lo)}) and {fixed(hi['first_failure'])} ({reason(hi)})"])
    return table(["design", "tolerated s", "first failure"], rows)


def compute_blocks(r: dict) -> dict[str, str]:
    """Every generated block from the results of :func:`run_stages`.

    Parameters
    ----------
    r : dict
        :func:`run_stages`.

    Returns
    -------
    dict
        Block name (:data:`BLOCKS`) → its Markdown text.
    """
    return {name: globals()[f"block_{name}"](r) for name in BLOCKS}


def fresh_blocks(workers: int | None = None) -> dict[str, str]:
    """Run the stages into a temporary results root and compute every block.

    Parameters
    ----------
    workers : int, optional
        Worker processes of the sweep.

    Returns
    -------
    dict
        Block name → Markdown text.
    """
    with tempfile.TemporaryDirectory(prefix="readme-numbers-") as tmp:
        return compute_blocks(run_stages(Path(tmp), workers))


# ------------------------------------------------------------------------------ README text
def read_blocks(text: str) -> dict[str, str]:
    """The generated blocks of a README text.

    Parameters
    ----------
    text : str
        The README.

    Returns
    -------
    dict
        Block name → text between its markers.

    Raises
    ------
    ValueError
        A block appears twice.
    """
    found: dict[str, str] = {}
    for m in _BLOCK_RE.finditer(text):
        if m["name"] in found:
            raise ValueError(f"README block {m['name']!r} appears twice")
        found[m["name"]] = m["body"]
    return found


def replace_blocks(text: str, blocks: dict[str, str]) -> str:
    """``text`` with each generated block's body replaced by ``blocks[name]``.

    Parameters
    ----------
    text : str
        The README.
    blocks : dict
        Block name → new text.

    Returns
    -------
    str
        The new README.

    Raises
    ------
    ValueError
        A block of ``blocks`` has no markers in ``text``.
    """
    missing = sorted(set(blocks) - set(read_blocks(text)))
    if missing:
        raise ValueError(f"README has no markers for {missing}")

    def sub(m):
        return f"<!-- generated:{m['name']} -->\n{blocks.get(m['name'], m['body'])}<!-- /generated:{m['name']} -->"
    return _BLOCK_RE.sub(sub, text)


def check(text: str, blocks: dict[str, str]) -> list[str]:
    """The blocks of ``text`` that differ from ``blocks`` (or are missing), with the first
    differing line.

    Parameters
    ----------
    text : str
        The README.
    blocks : dict
        Block name → expected text.

    Returns
    -------
    list of str
        One line per wrong block; empty when the README holds every block.
    """
    have = read_blocks(text)
    bad = []
    for name, want in blocks.items():
        got = have.get(name)
        if got is None:
            bad.append(f"{name}: no <!-- generated:{name} --> block in README.md")
        elif got != want:
            line = next((f"README {a!r} != computed {b!r}" for a, b in
                         zip(got.splitlines(), want.splitlines()) if a != b), "different length")
            bad.append(f"{name}: {line}")
    return bad


def main(argv: list[str] | None = None) -> int:
    """Rewrite (or ``--check``) the generated blocks of README.md from a fresh run.

    Parameters
    ----------
    argv : list of str, optional
        Command-line arguments.

    Returns
    -------
    int
        0, or 1 when ``--check`` found a wrong block.
    """
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--check", action="store_true", help="compare only; exit 1 when a block differs")
    ap.add_argument("--readme", type=Path, default=README)
    ap.add_argument("--workers", type=int, default=None, help="sweep workers (default: min(2, CPUs))")
    args = ap.parse_args(argv)
    blocks = fresh_blocks(args.workers)
    text = args.readme.read_text(encoding="utf-8")
    if args.check:
        bad = check(text, blocks)
        for line in bad:
            print(line)
        return 1 if bad else 0
    new = replace_blocks(text, blocks)
    if new != text:
        args.readme.write_text(new, encoding="utf-8")
    print(f"{args.readme}: {len(blocks)} generated blocks {'rewritten' if new != text else 'unchanged'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
