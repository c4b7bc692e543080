"""Outside file formats, one module per format, each a load/dump pair around :class:`StereoProfile`.

Layout (imports run one way): ``detect`` and ``mono`` (every format behind one loader) above the formats --
``opencv``, ``slam_settings``, ``kalibr``, ``zed``, ``ros`` with ``ros_read``, :mod:`s2r.formats.realsense`
(``rs-enumerate-devices`` text and librealsense recordings) -- above ``_common`` (strict numbers, profile assembly,
provenance), ``filestorage`` and ``s2r_yaml`` (the canonical profile YAML). Beside :mod:`s2r.sources` in the
layers (neither imports the other).
"""
