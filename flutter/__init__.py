"""Flutter: p-k solver, root tracking, crossings and modal participation.

Conventions (stated once, used everywhere): the p-k eigenvalue is p = omega * (gamma + i) as in
Nastran PK, the plotted damping is g = 2 * gamma, and structural damping g_s enters as i * g_s * K_hh.
"""
