"""Covariance propagation: step recursion, Kelly transition matrix, closed forms."""

__all__: list[str] = []
