"""planners: see README (later issues)."""
