"""Laban effort features and classifiers (later issues)."""
