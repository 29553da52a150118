"""Discovery: find where simulation and test disagree, name the missing physical effect from a
library (``effects``), add it, and show the gap shrink.

``discover`` and ``DiscoveryResult`` are loaded on first use (PEP 562 ``__getattr__``): the
workflow pulls in ``scipy.stats``, the candidates and the twins (over a second), and the modules
that need only ``discovery.effects`` or ``discovery.settings`` (``config``, every command that
reads a study file) would pay for it through this package's ``__init__`` otherwise.
"""

from typing import TYPE_CHECKING

from bayesupdate.discovery.settings import DiscoverySettings

if TYPE_CHECKING:  # the lazy names' module, for type checkers and the import-graph checks
    from bayesupdate.discovery.workflow import DiscoveryResult, discover

__all__ = ["DiscoveryResult", "DiscoverySettings", "discover"]


def __getattr__(name: str):
    if name in ("DiscoveryResult", "discover"):
        from bayesupdate.discovery import workflow

        return getattr(workflow, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
