"""Fault estimation: sizes of faults from residuals (e.g. additive vs multiplicative steering faults)."""
