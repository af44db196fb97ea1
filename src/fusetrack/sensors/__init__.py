"""fusetrack.sensors (see DESIGN.md)."""
