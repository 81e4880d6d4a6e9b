"""The action library and its loader (later issues)."""
