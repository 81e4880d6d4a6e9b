"""The action library: definitions, the built-in clips, user libraries and their loader."""
