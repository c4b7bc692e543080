"""Report stage: the HTML calibration report and its figures (loads matplotlib). Imports the other stages."""

from s2r.calib.report.html import calibration_sections, write_calibration_report

__all__ = ["calibration_sections", "write_calibration_report"]
