"""models: see README (later issues)."""
