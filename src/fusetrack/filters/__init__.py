"""fusetrack.filters (see DESIGN.md)."""
