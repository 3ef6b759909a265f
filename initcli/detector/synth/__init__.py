"""Rendering storeys of a site model into labelled images (``bim-init detector synth``): no torch."""
