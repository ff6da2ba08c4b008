"""One module per report section (the closing three, printed numbers, determinism and provenance,
are written by :mod:`acmm.report.build`); each part (a ``build(ctx, ...)`` or, where a section has
several parts, :data:`acmm.report.plan.PARTS`'s functions) takes declared inputs and writes its
share of the section (text, tables, figures, ledger entries) into its own
:class:`acmm.report.context.SectionWriter`."""
