"""Residual-generator synthesis: plain functions that return a design (generator + report)."""

from fdikit.design.observer import ObserverDesign, kalman, observer, observer_generator, unobservable_modes

__all__ = ["ObserverDesign", "kalman", "observer", "observer_generator", "unobservable_modes"]
