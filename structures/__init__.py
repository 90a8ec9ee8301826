"""Structures: Nastran bulk data to FE model, modes, mass properties, correlation and tuning."""
