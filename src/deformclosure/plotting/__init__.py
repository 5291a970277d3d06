"""Plots (matplotlib, imported lazily). Every function takes ``ax=None`` and returns the axes."""
