"""The ground floor: errors, quaternions, the doodle data model, tokens, atomic files,
smooth profiles and ARAP. Imports nothing of the project's own."""
