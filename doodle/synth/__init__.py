"""Seeded performers: one stroke per token (:mod:`.strokes`), people's styles
(:mod:`.performers`) and the minimal doodle of an implicit action (:mod:`.implicit`)."""
