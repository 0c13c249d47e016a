"""The one version of rostools (``pyproject.toml`` reads it; ``rostools.__version__`` is it).

A module of its own, at the bottom of the layers, so that any module may say which version
wrote something (the MCAP header's ``library``, ``-V``) without importing the package root,
which stands above everything (ARCHITECTURE.md).
"""

__version__ = "0.1.0"
