"""The names of the sampler's move schemes (``inference.sampling``'s module docstring) and
the checks of their settings, apart from the sampler: a study file's ``[sampler] moves`` is
checked by every command that prepares a study (``pipelines.study.prepare``), before any model
is built, and its ``adapt_steps`` when the file is read (``config.SamplerConfig``);
``calibrate`` or ``discover`` should not load emcee and the sampler's moves for that."""

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


#: the fewest steps of an adaptation stage of the "mixture" moves (``moves.staged``)
MIN_ADAPT_STEPS = 20


def check_adapt_steps(steps: int) -> int:
    """``steps`` if an adaptation stage may be that long, else BayesUpdateError (one line)."""
    if steps < MIN_ADAPT_STEPS:
        raise BayesUpdateError(f"sampler.adapt_steps: {steps}; use at least {MIN_ADAPT_STEPS}")
    return steps
