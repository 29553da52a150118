"""Where and how work runs, below every layer that models anything: the on-disk cache of
computed arrays (``cache``).  Imports nothing above the core."""

from bayesupdate.compute.cache import ArrayStore, CacheInfo, content_key, default_directory

__all__ = ["ArrayStore", "CacheInfo", "content_key", "default_directory"]
