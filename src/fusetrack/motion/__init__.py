"""fusetrack.motion (see DESIGN.md)."""
