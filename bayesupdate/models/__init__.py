"""Built-in structures, looked up by name with ``get_model``.

``exhaust``: the seed's exhaust system (Lupea 2013); ``exhaust_shell``: the same with shell
bodies (catalyst, mufflers).  ``shear_building``: the two-DOF shear building
used to verify the sampler against quadrature.  Each factory returns a ``ParametricModel``.
A Nastran deck is a model source too, resolved beside these by
``pipelines.model_source.resolve_model`` (this package reads no deck).
"""

import importlib

from bayesupdate.errors import BayesUpdateError

#: model name -> "module:factory" (imported lazily, so the CLI starts fast)
BUILTIN_MODELS = {
    "exhaust": "bayesupdate.models.exhaust:build_exhaust_model",
    "exhaust_shell": "bayesupdate.models.exhaust_shell:build_exhaust_shell_model",
    "shear_building": "bayesupdate.models.shear_building:build_shear_building_model",
}


def get_model(name: str, **options):
    """Return the built-in model ``name`` (see ``BUILTIN_MODELS``) built with the factory's
    keyword ``options``.  A Nastran deck or a ``package.module:function`` model:
    ``pipelines.model_source.resolve_model``."""
    if name not in BUILTIN_MODELS:
        raise BayesUpdateError(
            f"unknown model {name!r}; built-in models are {sorted(BUILTIN_MODELS)} (a Nastran "
            "deck or 'package.module:function': bayesupdate.pipelines.model_source.resolve_model)"
        )
    module_name, factory = BUILTIN_MODELS[name].split(":")
    return getattr(importlib.import_module(module_name), factory)(**options)
