"""fusetrack.perception (see DESIGN.md)."""
