"""Tangential solvers: one file per method."""
