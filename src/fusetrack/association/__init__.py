"""fusetrack.association (see DESIGN.md)."""
