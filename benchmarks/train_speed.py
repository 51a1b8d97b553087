"""Training speed of one run: Empathic DQN (the suite's runner and learner) vs Stable-Baselines3 DQN.

Both train on Coexistence with the paper's MLP (25 → 128 → 128 → 5), batch 32, one gradient step
per env step, the same ``learning_starts`` and replay size, ε already at its final 0.01 in the
timed window (so both pay the greedy forward pass on almost every step) and the same torch thread
count (1 by default: the fastest for these small networks):

* Empathic DQN at β = 0.5 (so ``Q`` and ``Q_emp`` both take a gradient step every env step),
  driven by ``empathy_zoo.training.runner.train_runs`` (one run, K = 1);
* SB3 DQN through its own ``learn()`` on the Gymnasium adapter (``empathy_zoo.gym_adapter``).

Each is timed over ``--steps`` env steps that start ``--settle`` steps after its warm-up; the
two alternate ``--repeats`` times and the medians are reported. Rates are given per wall-clock
second and per CPU second of this process (``time.process_time``): on a shared machine the
second is the steadier figure. Prints both rates of both, the ratios, the command and the machine.

    python benchmarks/train_speed.py [--steps 5000] [--warmup 1000] [--settle 200] [--repeats 3] [--threads 1] [--breakdown]
"""

from __future__ import annotations

import argparse
import os
import shlex
import statistics
import sys
import tempfile
import time

import numpy as np
import torch
from machine import describe_machine  # benchmarks/machine.py (this directory is on sys.path)

from agents.base import Method
from agents.empathic_dqn import EmpathicDQN
from agents.settings import EmpathicDQNSettings
from empathy_zoo.experiment.model import RunSpec
from empathy_zoo.training import RunnerOptions, train_runs

REPLAY = 500_000
FINAL_EPSILON = 0.01


class Stopwatch:
    """Times between two env-step counts of a run."""

    def __init__(self) -> None:
        self.arm(0, 0)

    def arm(self, start_step: int, end_step: int) -> None:
        self.start_step, self.end_step = start_step, end_step
        self.started = self.stopped = (float("nan"), float("nan"))

    def tick(self, step: int) -> None:
        if step == self.start_step:
            self.started = (time.perf_counter(), time.process_time())
        elif step == self.end_step:
            self.stopped = (time.perf_counter(), time.process_time())

    def rates(self) -> tuple[float, float]:
        """Env steps per wall-clock second and per CPU second of this process."""
        steps = self.end_step - self.start_step
        return steps / (self.stopped[0] - self.started[0]), steps / (self.stopped[1] - self.started[1])


STOPWATCH = Stopwatch()


class TimedEmpathicDQN(EmpathicDQN):
    """Empathic DQN that reports its env-step count to :data:`STOPWATCH` after every step."""

    def observe(self, batch) -> None:
        super().observe(batch)
        STOPWATCH.tick(self.env_steps)


TIMED_EMPATHIC_DQN = Method(
    name="timed_empathic_dqn",
    learner=TimedEmpathicDQN,
    settings=EmpathicDQNSettings,
    description="Empathic DQN with a stopwatch",
)


def empathic_dqn_rates(
    warmup: int, settle: int, steps: int, method: str = f"{__name__}:TIMED_EMPATHIC_DQN"
) -> tuple[float, float]:
    """Env steps per CPU second (before, after the warm-up) of one Empathic DQN run (K = 1, β = 0.5)
    through ``train_runs``, timed by :data:`STOPWATCH` in the learner ``method`` names."""
    settings = {
        "selfishness": 0.5,
        "batch_size": 32,
        "learning_starts": warmup,
        "replay_capacity": REPLAY,
        "epsilon_end": FINAL_EPSILON,
        "epsilon_decay_steps": 1,
    }
    start = warmup + settle
    spec = RunSpec.of(
        env="coexistence_v0",
        method=method,
        settings=settings,
        seed=0,
        steps=start + steps,
        eval_interval=10 * (start + steps),
        eval_episodes=1,
    )
    STOPWATCH.arm(start, start + steps)
    with tempfile.TemporaryDirectory(prefix="ez-train-speed-") as out:
        train_runs([spec], out, RunnerOptions(progress=False, checkpoint_interval=0))
    return STOPWATCH.rates()


def sb3_dqn_rates(warmup: int, settle: int, steps: int) -> tuple[float, float]:
    from stable_baselines3.common.callbacks import BaseCallback

    from baselines.sb3 import SB3Settings, make_sb3_model
    from empathy_zoo.gym_adapter import make_single_agent_env

    class Tick(BaseCallback):
        def _on_step(self) -> bool:
            STOPWATCH.tick(self.num_timesteps)
            return True

    start = warmup + settle
    settings = SB3Settings(
        algorithm="dqn",
        learning_rate=1e-3,
        batch_size=32,
        net_arch=(128, 128),
        algorithm_kwargs={
            "buffer_size": REPLAY,
            "learning_starts": warmup,
            "train_freq": 1,
            "gradient_steps": 1,
            "exploration_fraction": warmup / (start + steps),
            "exploration_final_eps": FINAL_EPSILON,
        },
    )
    model = make_sb3_model(settings, make_single_agent_env("coexistence_v0"), seed=0)
    STOPWATCH.arm(start, start + steps)
    model.learn(start + steps, callback=Tick())
    return STOPWATCH.rates()


def breakdown(rounds: int = 15, calls: int = 100) -> dict[str, float]:
    """CPU µs per call of the per-step pieces of both, the pieces interleaved round by round
    (median over rounds), so a busy machine slows them alike."""
    from baselines.sb3 import SB3Settings, make_sb3_model
    from empathy_zoo.environments import DEFAULT_POLICIES
    from empathy_zoo.gym_adapter import make_single_agent_env
    from empathy_zoo.vector import VectorEnv

    rng = np.random.default_rng(0)
    venv = VectorEnv("coexistence_v0", 1, fixed=DEFAULT_POLICIES["coexistence_v0"])
    obs = venv.reset(seed=0)[:, None, 0]
    learner = EmpathicDQN([EmpathicDQNSettings(selfishness=0.5, learning_starts=64, replay_capacity=REPLAY)], [0], venv.obs_size)
    row = torch.as_tensor(obs)
    flags = torch.ones((1, 1), dtype=torch.bool)
    one = torch.ones((1, 1, 1), dtype=torch.bool)  # one other agent, present
    step = torch.zeros((1, 1), dtype=torch.long), torch.ones((1, 1)), ~flags  # action, reward, terminated
    add = lambda: learner.replay.add(row, row, row[:, :, None], *step, one, one, ~one)  # noqa: E731
    for _ in range(300):
        add()
    model = make_sb3_model(
        SB3Settings(
            algorithm="dqn",
            learning_rate=1e-3,
            batch_size=32,
            algorithm_kwargs={
                "buffer_size": REPLAY,
                "learning_starts": 200,
                "exploration_fraction": 0.01,
                "exploration_final_eps": FINAL_EPSILON,
            },
        ),
        make_single_agent_env("coexistence_v0"),
        seed=0,
    )
    model.learn(400)
    pieces = {
        "Empathic DQN: learner.update (Q and Q_emp gradient steps)": learner.update,
        "Empathic DQN: learner.act (ε-greedy on Q_emp)": lambda: learner.act(obs),
        "Empathic DQN: VectorEnv.step (K = 1, swapped obs, cat)": lambda: venv.step(rng.integers(5, size=(1, 1))),
        "Empathic DQN: replay.add": add,
        "SB3 DQN: model.train (one gradient step)": lambda: model.train(gradient_steps=1, batch_size=32),
        "SB3 DQN: _sample_action (ε-greedy predict)": lambda: model._sample_action(0, None, 1),
        "SB3 DQN: VecEnv.step (DummyVecEnv, Monitor, adapter)": lambda: model.env.step(rng.integers(5, size=1)),
        "SB3 DQN: replay_buffer.add": lambda: model.replay_buffer.add(
            obs[0], obs[0], np.zeros((1, 1)), np.ones(1), np.zeros(1), [{}]
        ),
    }
    times: dict[str, list[float]] = {name: [] for name in pieces}
    for _ in range(rounds):
        for name, piece in pieces.items():
            started = time.process_time()
            for _ in range(calls):
                piece()
            times[name].append((time.process_time() - started) / calls * 1e6)
    return {name: statistics.median(values) for name, values in times.items()}


def machine() -> list[str]:
    import stable_baselines3

    return describe_machine(
        f"torch {torch.__version__} ({torch.get_num_threads()} thread(s))", f"stable-baselines3 {stable_baselines3.__version__}"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=5000, help="timed env steps of each run")
    parser.add_argument("--warmup", type=int, default=1000, help="learning_starts of both")
    parser.add_argument("--settle", type=int, default=200, help="untimed learning steps before the timed ones")
    parser.add_argument("--repeats", type=int, default=3, help="alternating measurements of each")
    parser.add_argument("--threads", type=int, default=1, help="torch threads of both")
    parser.add_argument("--breakdown", action="store_true", help="also time the per-step pieces of both")
    args = parser.parse_args()
    torch.set_num_threads(args.threads)
    print("command: python " + shlex.join(sys.argv))
    print("\n".join(machine()), flush=True)
    ours, theirs = [], []
    for repeat in range(args.repeats):
        ours.append(empathic_dqn_rates(args.warmup, args.settle, args.steps))
        theirs.append(sb3_dqn_rates(args.warmup, args.settle, args.steps))
        print(
            f"repeat {repeat + 1}: Empathic DQN {ours[-1][0]:6.0f}/s wall {ours[-1][1]:6.0f}/s CPU; "
            f"SB3 DQN {theirs[-1][0]:6.0f}/s wall {theirs[-1][1]:6.0f}/s CPU",
            flush=True,
        )
    for clock, i in (("wall-clock", 0), ("CPU", 1)):
        a, b = statistics.median(r[i] for r in ours), statistics.median(r[i] for r in theirs)
        print(
            f"per {clock} second (median of {args.repeats}): Empathic DQN (runner, β = 0.5, Q and Q_emp updated) "
            f"{a:.0f} env-steps/s; SB3 DQN (learn() on the Gymnasium adapter) {b:.0f} env-steps/s; "
            f"ratio {a / b:.2f}× SB3 per run (target ≥ 3×)"
        )
    if args.breakdown:
        print("per-step pieces, CPU µs per call (interleaved, median of 15 rounds of 100 calls):")
        for name, micros in breakdown().items():
            print(f"  {name:58s} {micros:7.0f}")
    print(f"load average after: {' '.join(f'{x:.1f}' for x in os.getloadavg())}")


if __name__ == "__main__":
    main()
