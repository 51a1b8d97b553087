"""The version of empathy-zoo, written only here (``pyproject.toml`` reads it at build time)."""

__version__ = "0.6.0"
