"""The input side of spatial motion doodles: data model, files, signals, the Segmenter, the CLI."""
