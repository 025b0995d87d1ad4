"""Covariance propagation: step recursion, Kelly transition matrix, closed forms."""
