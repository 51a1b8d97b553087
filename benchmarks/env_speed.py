"""Environment speed: the PettingZoo face (N = 1) and the vector env (N environments as arrays).

For both environments, side by side:

* ``Empathy(FixedAgents(parallel_env))``: what a learner on the PettingZoo API steps, the fixed
  agent (cat: random walk; human: patrol) acting inside and every step's swapped observations in
  ``infos``; random learner actions, episodes reset as they end;
* bare ``parallel_env()``: random actions for every live agent;
* ``VectorEnv(env, N, fixed=...)`` at N = 1, 64 and 4096 with random learner actions (autoreset,
  final and swapped observations included), in env-steps per second (N × steps per second).

Each figure is the median of ``--repeats`` timings, per wall-clock second and per CPU second of
this process (``time.process_time``): on a shared machine the CPU figure is the steadier one.
Actions are drawn before the clock starts. Prints the table, the command and the machine.

    python benchmarks/env_speed.py [--repeats 3] [--scale 1.0]
"""

from __future__ import annotations

import argparse
import os
import shlex
import statistics
import sys
import time
from collections.abc import Callable

import numpy as np
import pettingzoo
from machine import describe_machine  # benchmarks/machine.py (this directory is on sys.path)

from empathy_zoo import ENVIRONMENTS, EmpathyWrapper, FixedAgents
from empathy_zoo.actions import NUM_ACTIONS
from empathy_zoo.environments import DEFAULT_POLICIES
from empathy_zoo.vector import VectorEnv

ENVS = ("coexistence_v0", "sharing_v0")
VECTOR_SIZES = (1, 64, 4096)
STEPS_PER_SECOND_GUESS = {"parallel": 20_000, "vector": 2_000_000}
"""Roughly the targets; they size each timing to about a second at ``--scale 1``."""


def timed(run: Callable[[], int], repeats: int) -> tuple[float, float]:
    """Median (wall, CPU) rates of ``run``, which returns how many steps it took."""
    wall, cpu = [], []
    for _ in range(repeats):
        w0, c0 = time.perf_counter(), time.process_time()
        steps = run()
        w1, c1 = time.perf_counter(), time.process_time()
        wall.append(steps / (w1 - w0))
        cpu.append(steps / max(c1 - c0, 1e-9))
    return statistics.median(wall), statistics.median(cpu)


def parallel_rates(name: str, wrapped: bool, steps: int, repeats: int) -> tuple[float, float]:
    env = ENVIRONMENTS[name].parallel_env()
    if wrapped:
        env = EmpathyWrapper(FixedAgents(env, DEFAULT_POLICIES[name]))
    actions = np.random.default_rng(0).integers(NUM_ACTIONS, size=steps).tolist()
    env.reset(seed=0)

    def run() -> int:
        for action in actions:
            env.step(dict.fromkeys(env.agents, action))
            if not env.agents:
                env.reset()
        return steps

    return timed(run, repeats)


def vector_rates(name: str, num_envs: int, steps: int, repeats: int) -> tuple[float, float]:
    vector = VectorEnv(name, num_envs, fixed=DEFAULT_POLICIES[name])
    pool = np.random.default_rng(0).integers(NUM_ACTIONS, size=(min(steps, 64), num_envs, 1))
    vector.reset(seed=0)

    def run() -> int:
        for t in range(steps):
            vector.step(pool[t % len(pool)])
        return steps * num_envs

    return timed(run, repeats)


def load() -> str:
    return " ".join(f"{x:.2f}" for x in os.getloadavg())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeats", type=int, default=3, help="timings per figure (the median is shown)")
    parser.add_argument("--scale", type=float, default=1.0, help="multiply every timing's length")
    args = parser.parse_args()

    load_before = load()
    rows: list[tuple[str, dict[str, tuple[float, float]]]] = []
    parallel_steps = max(1, int(STEPS_PER_SECOND_GUESS["parallel"] * args.scale))
    for label, wrapped in (("Empathy(FixedAgents(parallel_env)) steps/s", True), ("parallel_env steps/s", False)):
        rows.append((label, {name: parallel_rates(name, wrapped, parallel_steps, args.repeats) for name in ENVS}))
    for n in VECTOR_SIZES:
        steps = max(1, int(STEPS_PER_SECOND_GUESS["vector"] * args.scale / n))
        steps = min(steps, int(STEPS_PER_SECOND_GUESS["parallel"] * args.scale / 2))  # N = 1 is a python loop
        rows.append((f"VectorEnv N={n} env-steps/s", {name: vector_rates(name, n, steps, args.repeats) for name in ENVS}))

    width = max(len(label) for label, _ in rows)
    header = f"| {'setup':<{width}} | " + " | ".join(f"{name} wall | {name} CPU" for name in ENVS) + " |"
    print(header)
    print("| " + "-" * width + " | " + " | ".join("---: | ---:" for _ in ENVS) + " |")
    for label, figures in rows:
        cells = " | ".join(f"{figures[name][0]:,.0f} | {figures[name][1]:,.0f}" for name in ENVS)
        print(f"| {label:<{width}} | {cells} |")
    print()
    print("command: python " + shlex.join(sys.argv))
    for line in describe_machine(f"pettingzoo {pettingzoo.__version__}"):
        print(line)
    print(f"load average (1, 5, 15 min): {load_before} before, {load()} after")


if __name__ == "__main__":
    main()
