"""causal: see README (later issues)."""
