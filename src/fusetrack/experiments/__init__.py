"""fusetrack.experiments (see DESIGN.md)."""
