"""Spatial motion doodles: the ground floor (:mod:`doodle.core`), the input side
(:mod:`doodle.input`), the seeded performers (:mod:`doodle.synth`) and the application
(:mod:`doodle.app`: compile pipeline, recorder, replay, render, CLI)."""
