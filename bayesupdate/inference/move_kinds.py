"""The names of the sampler's move schemes (``inference.sampling``'s module docstring) and
their check, apart from the sampler: a study file's ``[sampler] moves`` is checked by every
command that prepares a study (``pipelines.study.prepare``), before any model is built, and
``calibrate`` or ``discover`` should not load emcee and the sampler's moves for it."""

from bayesupdate.errors import BayesUpdateError

#: the move schemes ``SamplerSettings.moves`` names: the staged mixture (default) and DE
MOVE_KINDS = ("mixture", "de")


def check_moves(kind: str) -> str:
    """``kind`` if it names a move scheme, else BayesUpdateError (one line)."""
    if kind not in MOVE_KINDS:
        raise BayesUpdateError(
            f"sampler.moves: unknown {kind!r}; use one of {', '.join(MOVE_KINDS)}"
        )
    return kind
