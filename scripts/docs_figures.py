#!/usr/bin/env python
"""The guide's figures (docs/img/*.png) from a fresh run of the packaged configs.

Runs ``acmm simulate staircase`` (which designs first) and ``qpp simulate qpp_siso`` into a
temporary results root (never ``runs/``) and writes the figures the guide embeds as palette PNGs
(128 colours), each well under the 200 kB that ``tests/test_docs.py`` allows.  Each PNG carries
what it was drawn from as text chunks (:func:`provenance`: the command and, for the stair-case,
its per-level peak CMG momentum to 3 significant digits), which a slow test compares with a fresh
run (``tests/acmm/stages/test_simulate.py``): a figure of an earlier design fails it.

Usage: python scripts/docs_figures.py        (make docs-figures)
"""
from __future__ import annotations

import os
import subprocess
import sys
import tempfile
from pathlib import Path

import h5py
from PIL import Image
from PIL.PngImagePlugin import PngInfo

REPO = Path(__file__).resolve().parent.parent
IMG = REPO / "docs" / "img"

#: (command, run name, figure file) of every figure the guide embeds
FIGURES = [
    (["acmm", "simulate", "staircase"], "staircase", "sim_summary.png"),
    (["acmm", "simulate", "staircase"], "staircase", "design_poles.png"),
    (["acmm", "simulate", "staircase"], "staircase", "design_path_margins.png"),
    (["qpp", "simulate", "qpp_siso"], "qpp_siso", "qpp_sim_sin10.png"),
]

_ENTRY = {"acmm": "from acmm.cli.app import main; main()", "qpp": "from qpp.cli import main; main()"}


def provenance(root: Path, command: list, name: str) -> dict:
    """The text chunks of a figure drawn from run ``name`` of ``command`` under ``root``."""
    out = {"acmm-qpp:command": " ".join(command)}
    sim = root / name / "sim.h5"
    if command[0] == "acmm" and sim.is_file():
        with h5py.File(sim, "r") as f:
            out["acmm-qpp:peak_momentum_ft_lbf_s"] = ",".join(f"{v:.3g}" for v in f["levels/peak_momentum"][()])
    return out


def main() -> int:
    env = {**os.environ, "MPLBACKEND": "Agg", "OPENBLAS_NUM_THREADS": "1",
           "PYTHONPATH": os.pathsep.join(filter(None, [str(REPO), os.environ.get("PYTHONPATH")]))}
    IMG.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="docs-figures-") as root:
        done = set()
        for command, name, figure in FIGURES:
            if tuple(command) not in done:
                subprocess.run([sys.executable, "-c", _ENTRY[command[0]], *command[1:],
                                f"output.root={root}"], check=True, env=env, cwd=root,
                               stdout=subprocess.DEVNULL)
                done.add(tuple(command))
            image = Image.open(Path(root) / name / figure).convert("RGB")
            info = PngInfo()
            for key, value in provenance(Path(root), command, name).items():
                info.add_text(key, value)
            image.quantize(colors=128, method=Image.Quantize.MEDIANCUT).save(IMG / figure, optimize=True,
                                                                             pnginfo=info)
            print(f"docs/img/{figure}: {(IMG / figure).stat().st_size // 1024} kB")
    return 0


if __name__ == "__main__":
    sys.exit(main())
