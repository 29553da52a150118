"""Candidates that are one model: computed once, reported under each of their names.

Two library effects can extend the model into the same structure: an added mass or a ground
spring is placed at the model node of a test point (``effects.effect_site``), and test points
read on one node (the mAEWing1's accelerometers 1/2, 3/4, ..., 19/20: each pair reads on one
beam node of v3.3) give one model under two names.  Their score tests and refits are then the
same computation, so each is made once, for the first candidate of its site, and its result
is given to the others under their own names (``twin_score``, ``twin_fit``).  Nothing else
changes: every name stays a candidate of the scan (its count sets the prior odds), is ranked,
refitted and compared as before, and two such names remain indistinguishable to the verdict
(their evidence is equal), as they were when each was computed on its own.

A candidate on a reduced basis (``reduced_candidates``) has a basis of its own and is always
computed itself.
"""

from dataclasses import replace

from bayesupdate.compute.executors import executor_or_serial
from bayesupdate.discovery.candidates import Candidate
from bayesupdate.discovery.effects import effect_site
from bayesupdate.discovery.evidence import ModelFit
from bayesupdate.fe.reduced import ReducedFEModel


def site(candidate: Candidate) -> tuple:
    """What makes ``candidate``'s model: its ``effects.effect_site`` on a full model; its own
    label on a reduced basis (never shared)."""
    model = candidate.model
    if isinstance(model, ReducedFEModel) or not hasattr(model, "structure"):
        return ("label", candidate.label)
    return effect_site(model, candidate.effect)


def first_of_site(candidates: list[Candidate]) -> list[int]:
    """(n,) index of the first candidate of each candidate's ``site``."""
    first: dict[tuple, int] = {}
    return [first.setdefault(site(c), i) for i, c in enumerate(candidates)]


def map_once(executor, fn, items: list, candidates: list[Candidate], shared, twin, progress=None):
    """``executor.map(fn, items, shared)`` made for the first item of each site only
    (``first_of_site`` of ``candidates``, one per item); another item's result is
    ``twin(result of its site's first, its candidate)``.  progress : the executor's callback,
    called for the items computed."""
    firsts = first_of_site(candidates)
    computed = sorted(set(firsts))
    done = executor_or_serial(executor).map(fn, [items[i] for i in computed], shared, progress)
    by_first = dict(zip(computed, done, strict=True))
    return [
        by_first[i] if i == f else twin(by_first[f], candidates[i]) for i, f in enumerate(firsts)
    ]


def count_once(candidates: list[Candidate]) -> int:
    """How many of ``candidates`` ``map_once`` computes."""
    return len(set(first_of_site(candidates)))


def twin_score(score, candidate: Candidate):
    """A ``localization.CandidateScore`` given to ``candidate`` (same site)."""
    return replace(score, candidate=candidate)


def twin_fit(fit: ModelFit, candidate: Candidate) -> ModelFit:
    """``fit`` (a candidate's refit) given to ``candidate`` of the same site: its label, kind,
    location and effect parameters' names, its model in the fit's problem; every number as
    fitted."""
    n_design = len(fit.names) - len(candidate.axes)
    problem = fit.space.problem
    problem = replace(
        problem, model=candidate.model, parameters=problem.parameters[:n_design] + candidate.axes
    )
    axes = fit.space.axes[:n_design] + candidate.axes
    space = replace(fit.space, problem=problem, axes=axes)
    effect = candidate.effect
    return replace(
        fit,
        label=candidate.label,
        kind=effect.kind,
        location=effect.location,
        names=tuple(a.name for a in axes),
        space=space,
    )
