"""Skeletons, BVH, terrain, trajectory transfer and stylisation (later issues)."""
