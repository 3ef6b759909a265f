"""The site model: typed records of one extracted storey and reader/writer pairs for each file.

Files of a ``bim-extract`` OUTDIR and their modules:

- ``features.csv``        -> :mod:`bimtools.site.features_csv`
- ``walls.geojson``       -> :mod:`bimtools.site.walls_geojson`
- ``map_<storey>.pgm/yaml`` -> :mod:`bimtools.site.occupancy_map` (images: :mod:`bimtools.site.map_image`)
- ``site.json``           -> :mod:`bimtools.site.manifest`

:func:`bimtools.site.load.load_site` reads a whole OUTDIR (or a bare features.csv).
"""
