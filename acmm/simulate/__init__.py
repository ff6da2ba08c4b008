"""The nonlinear closed-loop simulation (ch. 6): the compiled kernel, the scenario, the plain-numpy
reference right-hand side, and numba's cache and warm-up."""
