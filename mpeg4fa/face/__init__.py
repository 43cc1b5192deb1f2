"""The decoder face engine (built up in this package; see its modules)."""
