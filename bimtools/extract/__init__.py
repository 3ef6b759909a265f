"""From element meshes to a storey's site model: sections, floor plan, grid, features."""
