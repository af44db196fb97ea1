"""fusetrack.management (see DESIGN.md)."""
