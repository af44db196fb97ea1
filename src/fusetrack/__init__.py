"""fusetrack: tracking with networks of different sensors, fused in Bayesian filters.

The package is organised by stage (``docs/ARCHITECTURE.md``): ``core`` values, ``motion`` and
``sensors`` models, ``world`` geometry, ``filters``, ``management``, ``association``,
``perception``, ``estimation`` (model parameters from the filters' log-likelihood),
``evaluation`` and the reproduced ``experiments``.
"""

__version__ = "0.1.0"
