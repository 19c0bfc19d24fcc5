"""The `bsdflab` command line: a thin shell over the Python API (no physics here)."""
