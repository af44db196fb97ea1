"""Reproduction of Ercan, El Gamal and Guibas 2013 (ACM TOSN 9(2) 16): occlusion-aware camera-network
tracking and camera selection. One module per experiment; ``simulation`` is their shared run."""
