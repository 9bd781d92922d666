"""Reproduction of the published papers: run their protocols, compare with their numbers."""
