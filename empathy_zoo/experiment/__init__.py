"""The experiment model: what a run is, as typed objects resolved once, and how configuration
files (sweep files, ``train --config``) become them.

- :mod:`~empathy_zoo.experiment.model`: :class:`EnvVariant`, :class:`MethodEntry`,
  :class:`Budget` and :class:`RunSpec` (one run: the three and a seed).
- :mod:`~empathy_zoo.experiment.values`: TOML values checked against the annotations of the
  dataclasses they fill.
- :mod:`~empathy_zoo.experiment.sweep_file`: sweep files and the shipped profiles.
"""

from empathy_zoo.experiment.model import DEFAULT_METHOD, Budget, EnvVariant, MethodEntry, RunSpec, group_specs
from empathy_zoo.experiment.sweep_file import load_sweep, parse_sweep, profile_path, profiles
from empathy_zoo.experiment.values import SweepConfigError

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
