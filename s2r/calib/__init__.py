"""Chessboard detection, calibration solving and calibration inputs (folders, bags)."""
