"""Sim-versus-real validation: diffs, depth accuracy, verdicts and reports."""
