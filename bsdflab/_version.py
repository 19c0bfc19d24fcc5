"""The package version, in a module of its own so that modules in every layer can read it
without importing the package root (which re-exports the public API of several layers)."""

__version__ = "0.1.0"
