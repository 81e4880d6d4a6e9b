"""The ``doodle`` command: :mod:`.main` builds the parser, one module per command family."""
