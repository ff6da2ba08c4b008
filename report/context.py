"""What every report section receives: the gathered results, the figure directory and the mode,
and where it writes: its own document blocks and printed-number ledger entries."""
from __future__ import annotations

from pathlib import Path

from report.constants import SECTIONS
from report.document import Doc
from report.gather import Gathered
from report.ledger import PrintedNumber, check_printed, status_text


class SectionWriter:
    """Inputs of a section (``g``: the gathered results, ``figdir``, ``fast``) and its output:
    ``doc`` (its text, tables and figures) and ``ledger`` (its printed numbers).

    HDF5 files are read once per report (``results``, shared read-only between sections);
    sections pass values to each other only through explicit arguments and return values.
    """

    def __init__(self, g: Gathered, figdir: Path, fast: bool, results: dict | None = None):
        self.g, self.figdir, self.fast = g, figdir, fast
        self._results = {} if results is None else results
        self.doc = Doc()
        self.ledger: list[PrintedNumber] = []

    def section_writer(self) -> "SectionWriter":
        """A writer for the next section: same inputs, empty document and ledger."""
        return SectionWriter(self.g, self.figdir, self.fast, self._results)

    def run(self, key):
        return self.g.runs[key]

    def data(self, key):
        """The results file of stage ``key`` ("stage:name") as read by :func:`acmm.results.read_h5`."""
        from common.results import read_h5

        if key not in self._results:
            self._results[key] = read_h5(self.run(key).path)
        return self._results[key]

    def ledger_add(self, *args, **kw) -> PrintedNumber:
        pn = check_printed(*args, **kw)
        self.ledger.append(pn)
        return pn

    def status_text(self, pn: PrintedNumber) -> str:
        return status_text(pn)

    def section(self, key):
        title = dict(SECTIONS)[key]
        self.doc.h(1, title, key)
