"""The package's version (``koolio-pm --version``; pyproject.toml reads it here)."""

__version__ = "0.2.0"
