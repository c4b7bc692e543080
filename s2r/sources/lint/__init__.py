"""``s2r lint``: mistakes in a robot description's stereo pair, each with a severity, a place and a fix.

``rules`` runs every rule (:func:`~s2r.sources.lint.rules.lint_description`); ``geometry`` holds the baseline
rules (also used by the profile builder to refuse a bad pair), ``mjcf`` the rules of an MJCF pair.

Above the loader and the pair's profile (:mod:`s2r.sources.pair_profile`); :mod:`s2r.sources.profile_builder`
imports ``geometry``, nothing else of :mod:`s2r.sources` imports lint.
"""

__all__: list[str] = []
