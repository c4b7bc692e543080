"""The sensor model: how a camera's images and depth differ from a perfect render (pydantic, YAML on disk).

``s2r sensor fit`` measures it on a recording, a profile may carry it as its optional ``sensor:`` section, and
:mod:`s2r.sensor` applies it (render's images, ``s2r sensor apply`` on perfect depth). Every field is optional:
a figure the recording could not give is left out (None), never guessed.

Images (8-bit grey levels, "DN"; pixels of the camera's image):

- ``image_noise_dn``: image noise, the one meaning shared with ``render --noise`` and ``sensor fit``: the standard
  deviation of additive Gaussian noise in the GREY image the matcher and the fit read, grey levels of the 8-bit
  range, before 8-bit rounding (the fit takes rounding's 0.29 DN out; the render rounds again). Rendered as one
  plane shared by the colour channels, so a colour render's grey image carries it whole.
- ``blur_sigma_px``: the edge-spread sigma, pixels: the standard deviation of the Gaussian whose integral best
  fits a sharp edge's grey-level profile across it. Rendering applies it as a Gaussian blur on top of the
  render's own (PyBullet, supersample 2: 0.15 px measured on its board edges, so an applied 0.7 px measures
  0.73 px).

Device depth (in the left camera's pixel grid; disparity ``d = f B / Z`` with the profile's left ``f`` and
baseline ``B``):

- disparity noise ``sigma_d(Z) = subpixel_sigma_px + subpixel_growth_px_per_m * (Z - 1 m)`` pixels (at least 0);
- ``disparity_step_px``: sub-pixel quantisation step of the matcher (D4xx: 1/32 px), None = none;
- ``fill_rate_by_distance``: share of valid pixels on a surface at distance Z (linear between points, constant
  beyond the ends); each point's ``frames`` is how many frames it rests on (``sensor fit`` merges a distance
  bin of fewer than 3 frames with its neighbour, and flags a point that still rests on fewer);
- ``hole_scale_px``: standard deviation of the Gaussian that correlates the hole pattern (0 = independent
  pixels);
- ``edge_dropout_px``: width of the band without depth across a depth edge, pixels (both sides together).
"""

from __future__ import annotations

from typing import Literal

from pydantic import BaseModel, ConfigDict, Field, StrictFloat, StrictInt

__all__ = ["SENSOR_SCHEMA_VERSION", "FillPoint", "SensorModel"]

SENSOR_SCHEMA_VERSION: Literal[1] = 1


class _Model(BaseModel):
    model_config = ConfigDict(frozen=True, extra="forbid", allow_inf_nan=False, validate_default=True)


class FillPoint(_Model):
    """The fill rate of depth on a surface at one distance."""

    distance_m: StrictFloat = Field(gt=0)
    fill_rate_pct: StrictFloat = Field(ge=0, le=100)
    frames: StrictInt | None = Field(default=None, ge=1)  # frames it rests on (None: not stated)


class SensorModel(_Model):
    """Image noise and blur, and device-depth noise, quantisation, fill and dropout (module docstring)."""

    schema_version: Literal[1] = SENSOR_SCHEMA_VERSION
    image_noise_dn: StrictFloat | None = Field(default=None, ge=0, le=128)
    blur_sigma_px: StrictFloat | None = Field(default=None, ge=0, le=50)
    subpixel_sigma_px: StrictFloat | None = Field(default=None, ge=0, le=100)
    subpixel_growth_px_per_m: StrictFloat = Field(default=0.0, ge=-100, le=100)
    disparity_step_px: StrictFloat | None = Field(default=None, gt=0, le=1)
    fill_rate_by_distance: tuple[FillPoint, ...] = ()
    hole_scale_px: StrictFloat = Field(default=0.0, ge=0, le=100)
    edge_dropout_px: StrictFloat | None = Field(default=None, ge=0, le=1000)
    source: str = ""
    frames: StrictInt = Field(default=0, ge=0)

    def describe(self) -> str:
        """One line naming the fitted figures (the ones left out are not named)."""
        parts = []
        if self.image_noise_dn is not None:
            parts.append(f"image noise {self.image_noise_dn:.3g} DN")
        if self.blur_sigma_px is not None:
            parts.append(f"blur {self.blur_sigma_px:.3g} px")
        if self.subpixel_sigma_px is not None:
            parts.append(f"disparity noise {self.subpixel_sigma_px:.3g} px at 1 m ({self.subpixel_growth_px_per_m:+.3g}"
                         " px/m)")
        if self.fill_rate_by_distance:
            fills = ", ".join(f"{p.fill_rate_pct:.0f} % at {p.distance_m:.2g} m" for p in self.fill_rate_by_distance)
            parts.append(f"fill {fills}")
        if self.edge_dropout_px is not None:
            parts.append(f"edge dropout {self.edge_dropout_px:.3g} px")
        return "; ".join(parts) or "no figures"

    def disparity_sigma_px(self, distance_m: float) -> float:
        """Disparity noise (px) at ``distance_m`` metres (0 without a fitted ``subpixel_sigma_px``)."""
        if self.subpixel_sigma_px is None:
            return 0.0
        return max(self.subpixel_sigma_px + self.subpixel_growth_px_per_m * (distance_m - 1.0), 0.0)
