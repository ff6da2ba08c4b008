"""The nonlinear closed loop of plant, servo-compensator and observer (ch. 13–14)."""
