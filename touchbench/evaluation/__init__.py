"""Evaluation helpers that sit beside the protocols: metrics, scene calibration and
the scores of a live recognition stream."""
