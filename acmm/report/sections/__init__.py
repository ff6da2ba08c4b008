"""One module per report section (the closing three, printed numbers, determinism and provenance,
are written by :mod:`acmm.report.build`); each module declares its parts as its ``PARTS`` rows
(task name, section, private function, stage tasks read, parts whose values it takes, cost), which
:data:`acmm.report.plan.PARTS` puts together in section order; a part takes declared inputs and
writes its share of the section (text, tables, figures, ledger entries) into its own
:class:`acmm.report.context.SectionWriter`."""
