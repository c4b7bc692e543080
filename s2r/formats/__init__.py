"""Outside file formats, one module per format, each a load/dump pair around :class:`StereoProfile`."""
