"""Discovery: find where simulation and test disagree, name the missing physical effect from a
library (``effects``), add it, and show the gap shrink."""

from bayesupdate.discovery.settings import DiscoverySettings  # noqa: E402
from bayesupdate.discovery.workflow import DiscoveryResult, discover  # noqa: E402

__all__ = ["DiscoveryResult", "DiscoverySettings", "discover"]
