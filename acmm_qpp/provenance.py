"""Provenance of a results file: the git commit (and whether the checkout differs from it) and
the config hash, stored with the package version and the creation time as root attributes of
every HDF5 file (:func:`acmm_qpp.results.write_h5`).
"""
from __future__ import annotations

import hashlib
import subprocess
from functools import lru_cache
from pathlib import Path


@lru_cache(maxsize=1)
def _git_state() -> tuple[str, bool | None]:
    """(commit, whether tracked files have uncommitted changes) of the source tree, from one
    ``git status --porcelain=v2 --branch`` run once per process; ("unknown", None) outside a
    checkout or without git."""
    try:
        out = subprocess.run(["git", "status", "--porcelain=v2", "--branch", "--untracked-files=no"],
                             cwd=Path(__file__).resolve().parent, capture_output=True, text=True, timeout=5,
                             check=True)
    except (OSError, subprocess.SubprocessError):      # (a failing git: CalledProcessError)
        return "unknown", None
    lines = out.stdout.splitlines()
    oid = next((ln.split()[2] for ln in lines if ln.startswith("# branch.oid ")), "unknown")
    if oid == "(initial)":
        oid = "unknown"
    return oid, any(not ln.startswith("#") for ln in lines if ln.strip())


def git_commit() -> str:
    """The git commit of the source tree, or ``"unknown"``.

    Asked of git once per process (a subprocess per results file cost milliseconds each, and the
    code running is the one imported at start).

    Returns
    -------
    str
        The commit hash, or ``"unknown"``.
    """
    return _git_state()[0]


def git_dirty() -> str:
    """Whether the source tree differs from :func:`git_commit` in tracked files.

    Returns
    -------
    str
        ``"yes"`` (uncommitted changes: the commit alone does not say what code ran), ``"no"``,
        or ``"unknown"`` (not a git checkout, or no git).
    """
    dirty = _git_state()[1]
    return "unknown" if dirty is None else ("yes" if dirty else "no")


def config_hash(config_text: str) -> str:
    """SHA-256 of a canonical config text (first 16 hex digits).

    Parameters
    ----------
    config_text : str
        The canonical config text.

    Returns
    -------
    str
        The first 16 hex digits of the hash.
    """
    return hashlib.sha256(config_text.encode()).hexdigest()[:16]
