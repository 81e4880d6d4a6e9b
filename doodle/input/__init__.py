"""Samples in, tokens out: the doodle file format and importers, axis conventions, devices
and pose sources, lost-tracking repair, smoothing, the moving frame and the Segmenter."""
