"""Smallest admissible values used as lower bounds of strictly positive quantities."""

TINY_MASS = 1e-9  # kg
TINY_LENGTH = 1e-6  # m
TINY_INERTIA = 1e-12  # kg m^2
