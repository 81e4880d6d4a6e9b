"""The roof: the compile pipeline, placement, recording, replay, rendering and the CLI.
The only package that knows all the others; nothing imports it."""
