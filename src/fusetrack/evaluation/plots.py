"""The figure helpers under the name experiments, tools and tutorials import
(``from fusetrack.evaluation import plots``): everything is drawn in :mod:`.drawing`, the one
module that imports Matplotlib (issue 20); this module only re-exports its public names."""

from __future__ import annotations

from .drawing import *  # noqa: F403 (the re-export is this module's purpose)
from .drawing import __all__ as __all__
