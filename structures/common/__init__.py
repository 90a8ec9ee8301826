"""Plumbing every part of the project uses, and nothing else.

- :mod:`structures.common.errors`: the project's exception hierarchy and message composer;
- :mod:`structures.common.files`: atomic netCDF / text / JSON writes, all-or-nothing folders, output
  path checks, netCDF reading;
- :mod:`structures.common.nastran`: the one Nastran deck reader (file checks, then pyNastran).
"""
