"""emcee moves beyond DE: a frozen defensive Gaussian-mixture independence proposal, fitted in
stages before the kept run (``staged``) and checked for coverage of the posterior first
(``coverage``)."""

from bayesupdate.inference.moves.defensive_proposal import DefensiveProposal
from bayesupdate.inference.moves.gaussian_mixture import GaussianMixture, fit_gaussian_mixture
from bayesupdate.inference.moves.independence import IndependenceMove
from bayesupdate.inference.moves.staged import fit_proposal, mixture_moves, staged_proposal

__all__ = [
    "DefensiveProposal",
    "GaussianMixture",
    "IndependenceMove",
    "fit_gaussian_mixture",
    "fit_proposal",
    "mixture_moves",
    "staged_proposal",
]
