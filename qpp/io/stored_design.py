"""The gains of a ``qpp design`` run read back for ``qpp simulate`` (issue 16).

``qpp simulate`` used to run the whole design procedure of ch. 12.1 again (the H∞ search of
ch. 11 included) before simulating, even right after ``qpp design`` wrote the same gains.  It now
takes K1, Kc and H (eqs 10.5–10.6) from ``<run>/qpp_design.h5`` when that file was written from
the same resolved config (``config_hash``) by the same package version and git commit, the
source is that commit unchanged (:func:`source_unchanged`), and the gains read
back hash to the ``gains_sha256`` the design stored with them (an edited file is designed
again); otherwise it designs.  The gains are stored as float64, so the simulation is the same bit
for bit either way.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import h5py
import hashlib
from acmm_qpp import __version__
from acmm_qpp.provenance import config_hash, git_commit, git_dirty


@dataclass
class StoredDesign:
    """A design read back from ``qpp_design.h5``: what a simulation needs of it.

    Attributes
    ----------
    K1 : (m, n) array
        State-feedback gain (eq 10.6), plant input units per state unit.
    Kc : (m, q) array
        Compensator gain (eq 10.6), plant input units per compensator-state unit.
    H : (n, p) array
        Observer gain (eq 10.5, report's sign), state units per output unit per s.
    certified : bool
        Whether the design was certified (β1 ≤ m and the circle criterion).
    verdict : str
        The design's verdict line.
    path : pathlib.Path
        The file read.
    horizon_note : str
        The design's note when T ends before the nominal loop settles, "" otherwise
        (:attr:`qpp.design.certificate.DesignResult.horizon_note`).
    """

    K1: np.ndarray
    Kc: np.ndarray
    H: np.ndarray
    certified: bool
    verdict: str
    path: Path
    horizon_note: str = ""


def source_unchanged() -> bool:
    """Whether the code running is exactly a commit: the source tree is a git checkout whose
    tracked files have no uncommitted change (:func:`acmm_qpp.provenance.git_dirty`).

    A stage may reuse another stage's results only then: an edited or unknown source may compute
    something else.

    Returns
    -------
    bool
        True for a clean checkout; False when dirty, not a checkout, or git is missing.
    """
    return git_commit() != "unknown" and git_dirty() == "no"


def load_stored_design(path: Path, config_text: str) -> StoredDesign | None:
    """The gains in ``path`` when it was written from ``config_text`` by this code, else None.

    Parameters
    ----------
    path : pathlib.Path
        A ``qpp_design.h5`` (it may not exist).
    config_text : str
        The resolved config as YAML (:meth:`qpp.io.config.QppConfig.to_yaml`).

    Returns
    -------
    StoredDesign or None
        None when the file is missing, unreadable, from another config, version or commit.
    """

    if not Path(path).is_file():
        return None
    try:
        with h5py.File(path, "r") as f:
            a = f.attrs
            same = (a.get("stage") == "qpp design" and a.get("config_hash") == config_hash(config_text)
                    and a.get("package_version") == __version__
                    and a.get("git_commit") == git_commit())
            if not same or not source_unchanged():
                return None
            K1, Kc, H = (np.array(f[k][()], dtype=float) for k in ("K1", "Kc", "H"))
            if a.get("gains_sha256") != gains_sha256(K1, Kc, H):
                return None
            note = a.get("horizon_note", "")
            return StoredDesign(K1, Kc, H, bool(a["certified"]), str(a["verdict"]), Path(path),
                                note.decode() if isinstance(note, bytes) else str(note))
    except (OSError, KeyError, ValueError):
        return None


def gains_sha256(K1, Kc, H) -> str:
    """SHA-256 of the gains' float64 bytes (with their shapes), stored by ``qpp design``.

    Parameters
    ----------
    K1, Kc, H : arrays
        The gains of eqs 10.5–10.6 (any units: the bytes are hashed).

    Returns
    -------
    str
        Hex digest.
    """
    h = hashlib.sha256()
    for g in (K1, Kc, H):
        g = np.ascontiguousarray(g, dtype=float)
        h.update(f"{g.shape}|".encode())
        h.update(g.tobytes())
    return h.hexdigest()
