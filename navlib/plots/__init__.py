"""Matplotlib figure builders, one module per domain; each returns a Figure."""
