"""Multi-target tracking from unlabelled bearings of several arrays, ghosts included (beyond the
papers; fusetrack issue 17): scenario, triangulation, methods, grid peaks, scoring, claims,
figures and text, run by :func:`.experiment.run` as ``multitarget-bearings``."""
