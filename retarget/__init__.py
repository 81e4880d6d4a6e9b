"""Skeletons and motion, BVH, terrain, trajectory transfer, animation stages, transitions, stylisation, IK and quality measures."""
