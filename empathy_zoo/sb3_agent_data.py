"""The ``data`` of a Stable-Baselines3 agent file, checked before SB3's ``load`` builds anything of it.

SB3's ``load`` sets every key of the JSON member ``data`` of its zip as an attribute of the model it
builds, then allocates what those keys size: the replay or rollout buffer (``buffer_size``,
``n_steps``, ``n_envs``) and the policy's networks (``policy_kwargs.net_arch``). An agent file may
come from anyone, so :func:`check_sb3_data` refuses, naming the file and the field, a key that
SB3's DQN or PPO does not write (:data:`DATA_KEYS`), a size out of its bound (:data:`SIZE_BOUNDS`),
a ``policy_kwargs`` key other than :data:`POLICY_KWARGS`, and networks of more layers than
:data:`MAX_NET_DEPTH`, a layer wider than :data:`~empathy_zoo.limits.MAX_HIDDEN_SIZE`, or more
weights than the file holds (an agent file stores every weight of its policy). The buffers serve
only training: the loader builds them one step long (:data:`ACTING_ONLY`), whatever ``data`` says.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping, Sequence
from typing import Any

from empathy_zoo.document_checks import DocumentChecker
from empathy_zoo.limits import MAX_HIDDEN_SIZE, MAX_STEPS, MAX_VECTOR_ENVS

__all__ = ["ACTING_ONLY", "DATA_KEYS", "MAX_NET_DEPTH", "POLICY_KWARGS", "SIZE_BOUNDS", "check_sb3_data", "policy_weights"]

_SHARED_KEYS = frozenset(
    {
        "_current_progress_remaining",
        "_episode_num",
        "_last_episode_starts",
        "_last_obs",
        "_last_original_obs",
        "_n_updates",
        "_num_timesteps_at_start",
        "_stats_window_size",
        "_total_timesteps",
        "action_noise",
        "action_space",
        "batch_size",
        "ep_info_buffer",
        "ep_success_buffer",
        "gamma",
        "learning_rate",
        "lr_schedule",
        "max_grad_norm",
        "n_envs",
        "n_steps",
        "num_timesteps",
        "observation_space",
        "policy_class",
        "policy_kwargs",
        "sde_sample_freq",
        "seed",
        "start_time",
        "tensorboard_log",
        "use_sde",
        "verbose",
    }
)
DATA_KEYS: Mapping[str, frozenset[str]] = {
    "DQN": _SHARED_KEYS
    | {
        "_n_calls",
        "batch_norm_stats",
        "batch_norm_stats_target",
        "buffer_size",
        "exploration_final_eps",
        "exploration_fraction",
        "exploration_initial_eps",
        "exploration_rate",
        "exploration_schedule",
        "gradient_steps",
        "learning_starts",
        "optimize_memory_usage",
        "replay_buffer_class",
        "replay_buffer_kwargs",
        "target_update_interval",
        "tau",
        "train_freq",
        "use_sde_at_warmup",
    },
    "PPO": _SHARED_KEYS
    | {
        "clip_range",
        "clip_range_vf",
        "ent_coef",
        "gae_lambda",
        "n_epochs",
        "normalize_advantage",
        "rollout_buffer_class",
        "rollout_buffer_kwargs",
        "target_kl",
        "vf_coef",
    },
}
"""The keys of ``data`` SB3's DQN and PPO write (Stable-Baselines3 2.x); an older file may lack some."""
SIZE_BOUNDS: Mapping[str, tuple[int, int]] = {
    "buffer_size": (1, MAX_STEPS),
    "n_steps": (1, MAX_STEPS),
    "n_envs": (1, MAX_VECTOR_ENVS),
    "batch_size": (1, MAX_STEPS),
    "_stats_window_size": (1, MAX_STEPS),
}
"""The sizes in ``data`` SB3 allocates by, and their bounds (a run's steps, a vector env's environments)."""
ACTING_ONLY: Mapping[str, Any] = {
    "buffer_size": 1,
    "n_steps": 1,
    "n_envs": 1,
    "replay_buffer_kwargs": {},
    "rollout_buffer_kwargs": {},
}
"""What the loader builds the replay or rollout buffer with in place of ``data``'s: a loaded agent only acts."""
POLICY_KWARGS = frozenset(
    {"net_arch", "normalize_images", "optimizer_kwargs", "ortho_init", "share_features_extractor", "log_std_init"}
)
"""The keys of ``policy_kwargs`` a loaded policy may be built with (its activation and classes are
SB3's defaults: a file naming others holds pickled objects, refused where they are read)."""
MAX_NET_DEPTH = 64
"""Most hidden layers of one network of a loaded policy (the suite's have two)."""
_DEFAULT_ARCH = [64, 64]
"""SB3's hidden layers where ``net_arch`` is not given (DQN's Q-network; PPO's policy and value networks each)."""


def _mlp_weights(widths: Sequence[int]) -> int:
    """Weights and biases of an MLP through ``widths`` (Python ints: no overflow)."""
    return sum(a * b + b for a, b in itertools.pairwise(widths))


def policy_weights(algorithm: str, arch: Any, obs_size: int, num_actions: int) -> int:
    """Weights SB3's ``MlpPolicy`` of ``algorithm`` holds with hidden layers ``arch`` (checked by
    :func:`check_sb3_data`): DQN's Q-network and its target; PPO's policy and value networks."""
    if algorithm == "DQN":
        return 2 * _mlp_weights([obs_size, *arch, num_actions])
    pi, vf = (arch.get("pi", []), arch.get("vf", [])) if isinstance(arch, Mapping) else (arch, arch)
    return _mlp_weights([obs_size, *pi, num_actions]) + _mlp_weights([obs_size, *vf, 1])


def _check_widths(check: DocumentChecker, widths: Any, field: str) -> list[int]:
    if not isinstance(widths, list) or len(widths) > MAX_NET_DEPTH:
        raise check.fail(field, f"a list of at most {MAX_NET_DEPTH} layer widths", widths)
    for i, width in enumerate(widths):
        check.integer(width, f"{field}[{i}]", 1, MAX_HIDDEN_SIZE)
    return widths


def _check_policy_kwargs(check: DocumentChecker, algorithm: str, kwargs: Any, field: str) -> Any:
    """``policy_kwargs`` of known keys and plain values; its ``net_arch`` (DQN: a list of widths;
    PPO: one, or ``{"pi": widths, "vf": widths}``) as given, or SB3's default."""
    kwargs = check.table(kwargs, field)
    unknown = sorted(set(kwargs) - POLICY_KWARGS)
    if unknown:
        raise check.fail(f"{field}.{unknown[0]}", f"no other key than {', '.join(sorted(POLICY_KWARGS))}", unknown[0])
    for name in ("normalize_images", "ortho_init", "share_features_extractor"):
        if name in kwargs and not isinstance(kwargs[name], bool):
            raise check.fail(f"{field}.{name}", "true or false", kwargs[name])
    if "log_std_init" in kwargs:
        check.finite(kwargs["log_std_init"], f"{field}.log_std_init")
    optimizer = check.table(kwargs.get("optimizer_kwargs") or {}, f"{field}.optimizer_kwargs")
    for name, value in optimizer.items():
        values = value if isinstance(value, list) and len(value) <= 4 else [value]
        if not all(item is None or isinstance(item, (bool, int, float)) for item in values):
            raise check.fail(f"{field}.optimizer_kwargs.{name}", "a number, a boolean or a short list of numbers", value)
    arch = kwargs.get("net_arch")
    if arch is None:
        return _DEFAULT_ARCH
    if algorithm == "PPO" and isinstance(arch, dict):
        if not arch or set(arch) - {"pi", "vf"}:
            raise check.fail(f"{field}.net_arch", '{"pi": widths, "vf": widths} or a list of widths', arch)
        return {name: _check_widths(check, widths, f"{field}.net_arch.{name}") for name, widths in arch.items()}
    return _check_widths(check, arch, f"{field}.net_arch")


def check_sb3_data(
    check: DocumentChecker, algorithm: str, saved: Mapping[str, Any], obs_size: int, num_actions: int, file_bytes: int
) -> None:
    """Refuse (``check``'s error, naming the file and the field) a ``data`` of SB3 ``algorithm``
    (``"DQN"``, ``"PPO"``) holding a key it does not write, a size out of its bound, or a policy
    whose networks, on ``obs_size`` inputs and ``num_actions`` actions, hold more float32 weights
    than the file's ``file_bytes`` bytes (see the module page)."""
    unknown = sorted(set(saved) - DATA_KEYS[algorithm])
    if unknown:
        raise check.fail(f"data.{unknown[0]}", f"none: SB3's {algorithm} writes no such key", saved[unknown[0]])
    for name, (low, high) in SIZE_BOUNDS.items():
        if name in saved:
            check.integer(saved[name], f"data.{name}", low, high)
    seed = saved.get("seed")
    if seed is not None:
        check.integer(seed, "data.seed", 0, 2**32 - 1)
    if saved.get("use_sde", False) is not False:
        raise check.fail("data.use_sde", "false (the suite's agents take discrete actions)", saved["use_sde"])
    arch = _check_policy_kwargs(check, algorithm, saved.get("policy_kwargs", {}), "data.policy_kwargs")
    weights = policy_weights(algorithm, arch, obs_size, num_actions)
    if weights * 4 > file_bytes:
        raise check.fail(
            "data.policy_kwargs.net_arch",
            f"networks the file holds (these take {weights:,} float32 weights, {math.ceil(weights * 4 / 2**20):,} MiB; "
            f"the file has {file_bytes:,} bytes)",
            arch,
        )
