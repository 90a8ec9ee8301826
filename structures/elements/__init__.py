"""Finite elements: element stiffness and mass kernels (pure, vectorised over elements)."""
