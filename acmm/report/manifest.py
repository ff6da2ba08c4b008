"""Determinism: SHA-256 of every HDF5 dataset the report used, and the comparison of two manifests."""
from __future__ import annotations

import hashlib
from datetime import datetime, timezone
from pathlib import Path

import numpy as np

from acmm.report.constants import TIMING_DATASETS
from acmm.report.gather import Gathered
import h5py
from acmm_qpp.results import dimension_only
from acmm_qpp.provenance import git_commit


def dataset_hashes(path: Path, exclude: tuple[str, ...] = TIMING_DATASETS) -> dict[str, str]:
    """SHA-256 (16 hex digits) of every dataset of an HDF5 file: dtype, shape and bytes.

    Attributes (creation time, commit) and the datasets named in ``exclude`` (timings) are left
    out, so two runs of the same computation hash equal exactly when their numbers are equal.

    Parameters
    ----------
    path : pathlib.Path
        The HDF5 file.
    exclude : tuple of str, optional
        Dataset names left out (any group).

    Returns
    -------
    dict
        Dataset path → hash, sorted by path.
    """

    out: dict[str, str] = {}

    def visit(name, obj):
        if isinstance(obj, h5py.Dataset) and name.rsplit("/", 1)[-1] not in exclude and not dimension_only(obj):
            arr = np.ascontiguousarray(obj[()])
            h = hashlib.sha256(f"{arr.dtype.str}|{arr.shape}|".encode())
            h.update(arr.tobytes() if arr.dtype.kind != "O" else repr(arr.tolist()).encode())
            out[name] = h.hexdigest()[:16]

    with h5py.File(path, "r") as f:
        f.visititems(visit)
    return dict(sorted(out.items()))


def build_manifest(g: Gathered) -> dict:
    """The manifest of a report: every stage file used with its hashes and dataset hashes.

    Parameters
    ----------
    g : acmm.report.gather.Gathered
        The gathered stage results.

    Returns
    -------
    dict
        ``created_utc``, ``git_commit`` and ``files`` (stage key → path, config and design
        hash, creation time, reused flag, :func:`dataset_hashes`).
    """
    files = {key: {"path": str(r.path), "config_hash": r.config_hash, "design_hash": r.design_hash,
                   "created_utc": r.created_utc, "reused": r.reused, "datasets": dataset_hashes(r.path)}
             for key, r in g.runs.items()}
    return {"created_utc": datetime.now(timezone.utc).isoformat(timespec="seconds"),
            "git_commit": git_commit(), "files": files}


def compare_manifests(old: dict | None, new: dict) -> dict:
    """Compare two manifests dataset by dataset.

    Parameters
    ----------
    old : dict or None
        The previous report's manifest (None: there is none).
    new : dict
        This report's manifest (:func:`build_manifest`).

    Returns
    -------
    dict
        ``status`` ("no previous report" | "identical" | "different" | "nothing comparable":
        no dataset of the previous report has this one's file and config), ``compared`` (number of
        datasets compared), ``recomputed`` (files recomputed since the previous report, i.e.
        with a different creation time), ``differences`` (list of "file: dataset"), ``missing``.
    """
    if not old:
        return {"status": "no previous report", "compared": 0, "recomputed": 0, "differences": [],
                "missing": [], "previous": None}
    diffs, missing, compared, recomputed = [], [], 0, 0
    for key, f in new["files"].items():
        o = old.get("files", {}).get(key)
        if o is None or o.get("config_hash") != f["config_hash"]:
            missing.append(key)
            continue
        recomputed += o.get("created_utc") != f["created_utc"]
        for ds, h in f["datasets"].items():
            if ds not in o["datasets"]:
                missing.append(f"{key}: {ds}")
            else:
                compared += 1
                if o["datasets"][ds] != h:
                    diffs.append(f"{key}: {ds}")
    # nothing in common (other results root, every config changed): no verdict to give
    status = "different" if diffs else "identical" if compared else "nothing comparable"
    return {"status": status, "compared": compared,
            "recomputed": recomputed, "differences": diffs, "missing": missing,
            "previous": old.get("created_utc")}
