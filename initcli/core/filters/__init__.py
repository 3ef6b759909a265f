"""Particle filters on the BIM occupancy map.

- :mod:`~initcli.core.filters.particle_filter` -- fine tuning (Eq. 18), AMCL-style tracking;
- :mod:`~initcli.core.filters.global_localisation` -- AMCL global localisation (the ``amcl`` baseline);
- :mod:`~initcli.core.filters.grid_cache` -- values derived from a map, built once per process.
"""
