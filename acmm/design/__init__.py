"""The controller design (ch. 5): Riccati solvers, the sector LQR and its methods, the gain
schedule and its refit, the path and robustness checks, and the design pipeline."""
