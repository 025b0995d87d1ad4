"""odomkit track / demo (placeholder, filled in by the foundation work)."""
