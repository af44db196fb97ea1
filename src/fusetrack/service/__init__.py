"""fusetrack.service (see DESIGN.md)."""
