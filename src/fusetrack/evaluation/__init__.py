"""fusetrack.evaluation (see DESIGN.md)."""
