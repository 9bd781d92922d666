"""Evaluation helpers that sit beside the protocols: metrics and scene calibration."""
