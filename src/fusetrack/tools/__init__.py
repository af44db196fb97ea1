"""Tools that run whole chains on a user's own data (``fusetrack track-video``)."""
