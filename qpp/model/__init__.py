"""The Lure plant (ch. 10.1): plant and servo-compensator, transfer functions and the
sector-bounded nonlinearities."""
