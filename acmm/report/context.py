"""What every report section receives: the gathered results, the figure directory and the mode,
and where it writes: its own document blocks and printed-number ledger entries."""
from __future__ import annotations

from pathlib import Path

from acmm.report.constants import SECTIONS
from acmm.report.document import Doc
from acmm.report.gather import Gathered
from acmm.report.ledger import PrintedNumber, check_printed
from acmm_qpp.results import read_h5


class SectionWriter:
    """Inputs of a section (``g``: the gathered results, ``figdir``, ``fast``) and its output:
    ``doc`` (its text, tables and figures) and ``ledger`` (its printed numbers).

    HDF5 files are read once per report (the ``results`` attribute, shared read-only between sections);
    sections pass values to each other only through explicit arguments and return values.

    Parameters
    ----------
    g : acmm.report.gather.Gathered
        The gathered configs and stage results.
    figdir : pathlib.Path
        Folder of the figures.
    fast : bool
        ``--fast`` mode (shortened runs).
    results : dict, optional
        Stage key → read HDF5 file, shared between the sections' writers.
    """

    def __init__(self, g: Gathered, figdir: Path, fast: bool, results: dict | None = None):
        self.g, self.figdir, self.fast = g, figdir, fast
        self.results = {} if results is None else results
        self.doc = Doc()
        self.ledger: list[PrintedNumber] = []

    def data(self, key):
        """The results file of stage ``key`` ("stage:name") as read by :func:`acmm_qpp.results.read_h5`.

        Parameters
        ----------
        key : str
            ``"<stage>:<config name>"``.

        Returns
        -------
        dict
            Dataset name → array (in the file's units), ``attrs`` → root attributes; read once
            per report.
        """
        if key not in self.results:
            self.results[key] = read_h5(self.g.runs[key].path)
        return self.results[key]

    def ledger_add(self, *args, **kw) -> PrintedNumber:
        """Classify a printed number (:func:`acmm.report.ledger.check_printed`) and add it to the ledger.

        Parameters
        ----------
        *args : tuple
            Passed on to :func:`acmm.report.ledger.check_printed`.
        **kw : dict
            Passed on to :func:`acmm.report.ledger.check_printed`.

        Returns
        -------
        acmm.report.ledger.PrintedNumber
            The entry added.
        """
        pn = check_printed(*args, **kw)
        self.ledger.append(pn)
        return pn

    def section(self, key):
        """Start the section ``key`` of :data:`acmm.report.constants.SECTIONS` (its heading).

        Parameters
        ----------
        key : str
            Section key.
        """
        self.doc.h(1, dict(SECTIONS)[key], key)
