"""Rectification, matching presets and the stereo depth pipeline."""
