"""Seeded randomness that stays identical whether an environment runs alone or in a batch.

Two tools:

* :class:`EnvStreams` keeps one ``gymnasium.utils.seeding.np_random`` generator per environment
  and hands out uniform numbers from a per-environment block, so a batched engine can draw for
  many environments with a handful of numpy calls while every environment still sees exactly the
  numbers its own generator would give it alone.
* :func:`counter_uniform` / :func:`counter_integers` are a counter-based generator (SplitMix64):
  the value depends only on ``(key, counter)``. Fixed policies and learners use it so a run's
  random stream does not depend on which other runs share its batch.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from gymnasium.utils import seeding

__all__ = [
    "STREAMS",
    "EnvStreams",
    "check_seed",
    "counter_bits",
    "counter_uniform",
    "counter_integers",
    "counter_integer",
    "derive_key",
]

STREAMS: dict[str, int] = {
    "fixed_agent": 1,  # + the agent's index: a fixed agent's seed from its environment's (policy_seed)
    "network_init": 11,  # a learner's initial weights (Empathic DQN)
    "exploration": 12,  # a learner's ε-greedy draws
    "replay_sample": 13,  # a learner's replay batches
    "sb3": 15,  # the seed handed to a Stable-Baselines3 algorithm
    "train_env": 20,  # a run's training environments
    "eval_env": 30,  # a run's greedy-evaluation start states (+ the episode)
    "heldout_eval": 31,  # a trained agent's held-out evaluation start states, every scenario alike (+ the episode)
    "attainable_utility": 40,  # AUP's auxiliary rewards, networks and replay batches (+ which of them)
    "considerate_value": 41,  # Be Considerate's value network of the other agent and its replay batches (+ which)
    "population_member": 50,  # a population partner's choice of member at each episode (from the episode's seed)
}
"""Every random stream derived from a run's seed, by name: ``derive_key(seed, STREAMS[name], ...)``.
One id per stream, so no two streams of a run ever coincide; a new stream takes a new id here."""
if len(set(STREAMS.values())) != len(STREAMS):
    raise AssertionError("two random streams share an id")

_GOLDEN = np.uint64(0x9E3779B97F4A7C15)
_MIX1 = np.uint64(0xBF58476D1CE4E5B9)
_MIX2 = np.uint64(0x94D049BB133111EB)
_MASK64 = (1 << 64) - 1


def counter_bits(key: np.ndarray | int, counter: np.ndarray | int) -> np.ndarray:
    """64 random bits per element from ``(key, counter)`` (SplitMix64 finaliser); broadcasts."""
    k = np.atleast_1d(np.asarray(key, dtype=np.uint64))
    c = np.atleast_1d(np.asarray(counter, dtype=np.uint64))
    z = k + (c + np.uint64(1)) * _GOLDEN
    z = (z ^ (z >> np.uint64(30))) * _MIX1
    z = (z ^ (z >> np.uint64(27))) * _MIX2
    return z ^ (z >> np.uint64(31))


def counter_uniform(key: np.ndarray | int, counter: np.ndarray | int) -> np.ndarray:
    """Uniform floats in ``[0, 1)`` from ``(key, counter)``; broadcasts."""
    return (counter_bits(key, counter) >> np.uint64(11)).astype(np.float64) * (1.0 / (1 << 53))


def counter_integers(key: np.ndarray | int, counter: np.ndarray | int, high: int | np.ndarray) -> np.ndarray:
    """Integers in ``[0, high)`` from ``(key, counter)``; broadcasts."""
    return np.floor(counter_uniform(key, counter) * high).astype(np.int64)


def counter_integer(key: int, counter: int, high: int) -> int:
    """``counter_integers`` of one ``(key, counter)`` in plain Python ints: the same value, without
    numpy's per-call overhead (a fixed agent acting in one environment draws one number a step)."""
    z = (int(key) + (int(counter) + 1) * int(_GOLDEN)) & _MASK64
    z = ((z ^ (z >> 30)) * int(_MIX1)) & _MASK64
    z = ((z ^ (z >> 27)) * int(_MIX2)) & _MASK64
    z ^= z >> 31
    return int((z >> 11) * (1.0 / (1 << 53)) * high)


def derive_key(seed: int, *stream: int) -> int:
    """A 64-bit key for the random stream ``stream`` of ``seed`` (via ``numpy.random.SeedSequence``)."""
    if seed is None or int(seed) < 0:
        raise ValueError(f"seed must be a non-negative int, got {seed!r}")
    return int(np.random.SeedSequence([int(seed), *map(int, stream)]).generate_state(1, np.uint64)[0])


MAX_ENV_SEED = 2**64 - 1
"""The largest seed an environment takes: 64 bits, as every key :func:`derive_key` makes."""


def check_seed(seed: int | None) -> int | None:
    """``seed`` if it is an int in ``0 … 2⁶⁴ − 1`` (or ``None``: fresh entropy), else ``ValueError``."""
    if seed is not None and (isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or not 0 <= seed <= MAX_ENV_SEED):
        shown = repr(seed) if not isinstance(seed, int) or seed.bit_length() <= 128 else f"an int of {seed.bit_length():,} bits"
        raise ValueError(f"seed must be an int in 0 … 2⁶⁴ − 1 (64 bits) or None, got {shown}")
    return seed


class EnvStreams:
    """One seeded generator per environment, drawn in blocks.

    ``uniform(env_ids)`` returns one float in ``[0, 1)`` for each listed environment; each
    environment's numbers come from its own ``np_random`` generator, ``block`` at a time, so the
    sequence an environment sees is the same for any batch it is part of.
    """

    def __init__(self, num_envs: int, block: int = 64) -> None:
        self.num_envs = num_envs
        self.block = block
        self.generators: list[np.random.Generator | None] = [None] * num_envs
        self.seeds: list[int | None] = [None] * num_envs
        self._buffer = np.zeros((num_envs, block), dtype=np.float64)
        self._position = np.full(num_envs, block, dtype=np.int64)

    def seed(self, env_id: int, seed: int | None) -> None:
        """(Re)seed environment ``env_id``; ``None`` draws fresh entropy, as Gymnasium does."""
        check_seed(seed)
        generator, used = seeding.np_random(None if seed is None else int(seed))
        self.generators[env_id] = generator
        self.seeds[env_id] = used
        self._position[env_id] = self.block

    def ensure_seeded(self, env_ids: Sequence[int] | np.ndarray) -> None:
        for i in env_ids:
            if self.generators[i] is None:
                self.seed(int(i), None)

    def uniform(self, env_ids: np.ndarray) -> np.ndarray:
        """One uniform number per entry of ``env_ids`` (distinct environment ids)."""
        env_ids = np.asarray(env_ids, dtype=np.int64)
        if env_ids.size == 0:
            return np.zeros(0)
        empty = env_ids[self._position[env_ids] >= self.block]
        for i in empty:
            generator = self.generators[i]
            if generator is None:
                self.seed(int(i), None)
                generator = self.generators[i]
            self._buffer[i] = generator.random(self.block)
            self._position[i] = 0
        values = self._buffer[env_ids, self._position[env_ids]]
        self._position[env_ids] += 1
        return values

    def state(self) -> dict:
        """Everything needed to continue the streams exactly (for checkpoints)."""
        return {
            "bit_generators": [None if g is None else g.bit_generator.state for g in self.generators],
            "seeds": list(self.seeds),
            "buffer": self._buffer.copy(),
            "position": self._position.copy(),
        }

    def load_state(self, state: dict) -> None:
        for i, bg_state in enumerate(state["bit_generators"]):
            if bg_state is None:
                self.generators[i] = None
            else:
                generator = np.random.Generator(np.random.PCG64())
                generator.bit_generator.state = bg_state
                self.generators[i] = generator
        self.seeds = list(state["seeds"])
        self._buffer[...] = state["buffer"]
        self._position[...] = state["position"]
