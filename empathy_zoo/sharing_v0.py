"""# Sharing

A robot and a human collect batteries on a small torus. Every battery is worth less to its
collector than the one before (diminishing returns), so a fair split gives the most total
value; a purely selfish robot grabs everything it can. This is the paper's second environment.

| | |
|---|---|
| Import | `from empathy_zoo import sharing_v0` |
| Agents | `robot_0` (the learner), `human_0` (fixed: `Patrol`, up on steps 0, 7, 14, …, else right) |
| Actions | `Discrete(5)`: 0 up (row−1), 1 down (row+1), 2 left (col−1), 3 right (col+1), 4 stay |
| Observations | `Box(-1, 1 + #batteries, (view·view,), float32)`: the `view×view` window around the agent, wrapping, row-major; floor `0`, battery `-1`, an agent `1 + batteries it has collected`; the own cell is drawn last |
| Parallel API | yes (`parallel_env`); AEC via `env` |

## Rules
* The world is a `size×size` torus; every move wraps. Both agents move at once.
* **Batteries**: one on every cell whose row and column are both odd (9 on the default 7×7).
* **Collecting**: an agent that ends its move on a battery collects it. If both end on the same
  battery in the same step, the env's seeded generator gives it to one of them (probability ½).
* **Start**: two distinct random cells without a battery.

## Rewards
Per agent and independent: its n-th battery is worth `1.1 − 0.1·n` (1.0, 0.9, …, 0.2). No other
reward.

## Termination and truncation
Everyone terminates when no battery is left; everyone is truncated after `max_cycles` steps.

## Infos
`infos[agent]["batteries"]`: batteries the agent has collected so far.

## Reset options
`reset(seed, options={"positions": {"robot_0": (r, c), ...}, "batteries": [(r, c), ...]})` places
agents and/or replaces the battery layout. Unknown agents, off-grid cells, two agents on one
cell, a battery listed twice, an empty battery list or a battery under an agent raise `ValueError`.

## Perspective swap
`env.unwrapped.swapped_observation(viewer, other, in_view_only=False)` exchanges cells *and*
battery counts (here: `other`'s own observation). Wrap with `empathy_zoo.EmpathyWrapper` to get
it in `infos`.

## Arguments
`sharing_v0.parallel_env(size=7, view=5, max_cycles=500, render_mode=None)`
* `size`: side of the torus (≥ 3). `view`: observation window (odd, < `size`).
* `max_cycles`: steps before truncation.
* `render_mode`: `None`, `"ansi"` (`R` robot, `H` human, `o` battery, `*` both agents) or `"rgb_array"`.

## Version history
* v0: first release, following the behaviour contract in docs/SPEC.md §1, §3.
"""

from __future__ import annotations

from empathy_zoo.engine.sharing import SharingEngine
from empathy_zoo.parallel import GridParallelEnv, env_constructors, grid_metadata

__all__ = ["raw_env", "parallel_env", "env"]


class raw_env(GridParallelEnv):  # noqa: N801 - PettingZoo naming
    """Sharing as a ``ParallelEnv`` (see the module documentation)."""

    engine_class = SharingEngine
    metadata = grid_metadata("sharing_v0")


parallel_env, env = env_constructors(raw_env)
