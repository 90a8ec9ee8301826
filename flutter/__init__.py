"""Flutter: the p-k solver (default), the g-method and the p-method on a rational fit, root tracking,
rigid-body roots, crossings, modal participation and the flight-mechanics short period.

Conventions (stated once, used everywhere): the p-k eigenvalue is p = omega * (gamma + i) as in
Nastran PK, the plotted damping is g = 2 * gamma, and structural damping g_s enters as i * g_s * K_hh.
"""
