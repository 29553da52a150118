"""bayesupdate: probabilistic finite-element model updating in structural dynamics.

Layers (see docs/architecture.md): ``fe`` (structures, modal solve), ``models`` (built-in
structures), ``ema`` (modal identification from tests), ``inference`` (calibration and posterior),
``discovery`` (missing physics), with ``modal_data`` and ``correlation`` as the shared hand-off, and
the CLI, files and plots at the edge.
"""

from bayesupdate.errors import BayesUpdateError

__version__ = "0.2.0"
__all__ = ["BayesUpdateError", "__version__"]
