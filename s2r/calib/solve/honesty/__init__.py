"""What a calibration's figures are worth: stereo held-out error and jackknife standard deviations over pairs
(``heldout``, ``resample``), the same for one camera (``mono_resample`` with its worker ``mono_fold``), which lens
model fits (``models``), projection uncertainty maps (``projection``), the corner-id paths' figures (``target``)
and the verdict a user can act on (``verdict``).

Imports the solvers (:mod:`s2r.calib.solve.solvers`) and :mod:`s2r.lens`; never the pipelines above it.
"""

__all__: list[str] = []
