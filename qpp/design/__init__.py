"""The design of ch. 11–12: H∞ gains, the circle criterion, the sphere bounds, the thresholds and
the guarantee certificate."""
