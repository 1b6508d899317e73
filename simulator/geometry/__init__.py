"""Geometry of crease patterns: patterns, their checks, polygons, materials and
example patterns."""
