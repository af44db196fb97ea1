"""fusetrack.world (see DESIGN.md)."""
