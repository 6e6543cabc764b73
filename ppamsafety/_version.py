"""The package version, recorded in every file the toolkit writes (marker files, JSON results)."""

__version__ = "0.1.0"
