"""One module per report section; each ``build(ctx, ...)`` takes declared inputs and writes its
section (text, tables, figures, ledger entries) into its own :class:`acmm.report.context.SectionWriter`."""
