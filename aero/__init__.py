"""Aerodynamics: panel geometry, steady VLM, doublet-lattice AICs, splines and GAFs.

Reduced frequency everywhere is Nastran's k = omega * b / V with b = REFC / 2.
"""
