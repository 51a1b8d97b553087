"""The experiment model: what a run is, as typed objects resolved once, and how configuration
files (sweep files, ``train --config``) become them.

- :mod:`~empathy_zoo.experiment.model`: :class:`EnvVariant`, :class:`MethodEntry`,
  :class:`Budget` and :class:`RunSpec` (one run: the three and a seed).
- :mod:`~empathy_zoo.experiment.values`: TOML values checked against the annotations of the
  dataclasses they fill.
- :mod:`~empathy_zoo.experiment.sweep_file`: sweep files and the shipped profiles.
- :mod:`~empathy_zoo.experiment.log_backends`: where runs may log their scalars.
- :mod:`~empathy_zoo.experiment.result_reader`: reading a result file, its method's settings checked.
"""

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # (imported on first use: see __getattr__)
    from empathy_zoo.experiment.model import DEFAULT_METHOD, Budget, EnvVariant, MethodEntry, RunSpec, group_specs
    from empathy_zoo.experiment.sweep_file import load_sweep, parse_sweep, profile_path, profiles
    from empathy_zoo.experiment.values import SweepConfigError

_HOMES = {
    **dict.fromkeys(("DEFAULT_METHOD", "Budget", "EnvVariant", "MethodEntry", "RunSpec", "group_specs"), "model"),
    **dict.fromkeys(("load_sweep", "parse_sweep", "profile_path", "profiles"), "sweep_file"),
    "SweepConfigError": "values",
}
"""The module of each name below: imported when first asked for, so that a module of this package
(the result reader) loads without the method registry that :mod:`.model` imports."""

__all__ = [
    "DEFAULT_METHOD",
    "Budget",
    "EnvVariant",
    "MethodEntry",
    "RunSpec",
    "SweepConfigError",
    "group_specs",
    "load_sweep",
    "parse_sweep",
    "profile_path",
    "profiles",
]


def __getattr__(name: str) -> Any:
    """A name of :data:`__all__`, from its module (imported on first use)."""
    if name in _HOMES:
        return getattr(importlib.import_module(f"empathy_zoo.experiment.{_HOMES[name]}"), name)
    raise AttributeError(f"module 'empathy_zoo.experiment' has no attribute {name!r}")
