"""The motion-token language: expressions, automata, the Matcher, shapes, the Contexter."""
