"""Simulation scenarios of the seeds, as functions that return :class:`~fdikit.trace.Trace` objects."""
