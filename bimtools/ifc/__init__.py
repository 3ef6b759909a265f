"""Reading IFC models: opening with clear errors, units, storeys, element text, geometry."""
