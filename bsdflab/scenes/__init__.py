"""Geometry builders, procedural scenes and scene files for bsdflab's path tracer."""
