"""``validate --recording``: the sim and real cameras measured on recordings (``compare``), side by side per
distance bin with bootstrap intervals (``bins``), as terminal lines and an HTML section (``report``).

Imports the measures, ``tolerances`` and ``verdict`` below it and :mod:`s2r.quality`; ``report`` reads the run's
result type.
"""

__all__: list[str] = []
