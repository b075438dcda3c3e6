"""Matplotlib figure builders, one module per domain; each returns a Figure."""

__all__ = ["allan", "assess", "covariance", "figure", "metrics", "observability", "outliers",
           "phases", "plan", "ssac", "sweep", "trajectory"]
