"""Readers and writers, one module per format. Side effects live here, not in the core."""

__all__: list[str] = []
