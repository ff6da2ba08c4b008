"""Matplotlib figures of the design and simulation stages (report Figs 5.3–5.26, 6.2–6.30)."""
