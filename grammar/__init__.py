"""The motion-token language: expressions, automata, the Matcher (later issues)."""
