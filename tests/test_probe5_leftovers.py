"""A fifth probe's leftovers (issue 33, "files from elsewhere are inert"): an evaluation file's
partners only for agents its scenario's world holds; a checkpoint's saved stream keys rederived
from the seeds of the runs it resumes; a study file's text and numbers checked field by field
before ``analyse tuning-summary`` puts them in a table."""

from __future__ import annotations

import copy
import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from empathy_zoo.cli import main
from empathy_zoo.evaluation_file import EvaluationFileError, check_evaluation
from empathy_zoo.fixed_agents import policy_seed
from empathy_zoo.partner_policies import Population
from empathy_zoo.policies import batched, make_policy
from empathy_zoo.run_ids import run_id
from empathy_zoo.vector import VectorEnv

DOCS = Path(__file__).resolve().parents[1] / "docs" / "results"
THREE_CATS = DOCS / "methods" / "evaluations" / "coexistence_v0" / "coexistence_3cats__dqn-8e5a283c__s0.json"


# ---------------------------------------------------------------------------- evaluation partners (#13)
def three_cats_evaluation() -> dict[str, Any]:
    """A shipped evaluation of a run beside three cats: ``trained_with`` holds cat_0 … cat_2, and
    its scenarios (one cat unless they say otherwise) their own."""
    return json.loads(THREE_CATS.read_text())


def test_the_shipped_evaluation_passes() -> None:
    check_evaluation(three_cats_evaluation(), THREE_CATS)


@pytest.mark.parametrize(
    "where, agent",
    [
        (("scenarios", 0, "fixed"), "cat_3"),  # the run's world: three cats
        (("scenarios", 1, "fixed"), "cat_1"),  # cat_stays: one cat
        (("scenarios", 1, "fixed"), "human_0"),  # no human in Coexistence
        (("scenarios", 1, "fixed"), "robot_0"),  # the learner is no partner
        (("scenarios", 1, "fixed"), "cat_01"),
        (("scenario_set", "scenarios", 0, "fixed"), "cat_1"),  # the set's definition of cat_stays
        (("scenario_set", "scenarios", 4, "fixed"), "cat_2"),  # two_random_cats: cat_0, cat_1
    ],
)
def test_an_evaluation_partner_for_an_agent_its_world_lacks_is_refused(where: tuple[Any, ...], agent: str) -> None:
    document = copy.deepcopy(three_cats_evaluation())
    table = document
    for key in where:
        table = table[key]
    table[agent] = "random_walk"
    with pytest.raises(EvaluationFileError) as refused:
        check_evaluation(document, "forged.json")
    message = str(refused.value)
    assert message.startswith("forged.json: field ") and f"(the agent {agent!r})" in message and "\n" not in message


def test_an_evaluation_partner_numbered_within_a_huge_count_is_checked_without_listing_them() -> None:
    document = copy.deepcopy(three_cats_evaluation())
    definition = document["scenario_set"]["scenarios"][0]  # (a definition's grid is checked when played)
    definition["env_kwargs"]["num_cats"] = 10**9
    definition["fixed"]["cat_999999999"] = "stay"
    with pytest.raises(EvaluationFileError, match=r"scenarios\[0\]\.fixed: expected a policy for each of the 1,000,000,000"):
        check_evaluation(copy.deepcopy(document), "forged.json")  # (a name within the count, the partners counted)
    definition["fixed"]["cat_1000000000"] = "stay"
    with pytest.raises(EvaluationFileError, match=r"'cat_1000000000'"):
        check_evaluation(document, "forged.json")


# ---------------------------------------------------------------------------- saved stream keys (#6)
SEED = 2024
"""The seed of every policy's last seeded reset below."""


def _stepped(policy: Any, steps: int = 7) -> Any:
    """``policy`` reset with :data:`SEED` and acted ``steps`` times: its key is the seed's, its count moved."""
    policy.reset(SEED)
    for _ in range(steps):
        policy.act(np.zeros(25, dtype=np.float32), {"step": 0, "agent": "cat_0", "size": 7, "positions": {}})
    return policy


@pytest.mark.parametrize("name", ["random_walk", "slow_walk", "noisy"])
def test_a_streams_saved_key_is_rederived_from_its_seed(name: str) -> None:
    policy: Any = _stepped(make_policy(name))
    state = policy.state()
    assert policy.saved_key_problem(state, SEED) is None
    forged = {**state, "key": state["key"] ^ 1}  # (a 64-bit key still: load_state alone takes it)
    fresh: Any = make_policy(name)
    fresh.load_state(forged)
    assert policy.saved_key_problem(forged, SEED) == f"key is {forged['key']}, not {state['key']}, the key its seed gives"
    assert policy.saved_key_problem({**state, "key": None}, SEED) is not None  # (None would draw a fresh key)
    assert policy.saved_key_problem(state, SEED + 1) is not None


def test_a_populations_saved_keys_are_rederived_its_own_and_its_first_members() -> None:
    population = Population(["random_walk", "slow_walk"])
    _stepped(population)
    state = population.state()
    first = population.member
    assert population.saved_key_problem(state, SEED) is None
    forged = {**state, "key": state["key"] ^ 1}
    assert str(population.saved_key_problem(forged, SEED)).startswith("key is ")
    members = copy.deepcopy(state["members"])
    members[first]["key"] ^= 1
    assert str(population.saved_key_problem({**state, "members": members}, SEED)).startswith(f"members[{first}].key is ")


def test_a_batched_streams_saved_keys_are_rederived_per_environment() -> None:
    fast: Any = batched(make_policy("random_walk"), 3)
    seeds = [policy_seed(s, 1) for s in (5, 6, 7)]
    fast.reset(np.arange(3), seeds)
    fast.act(None, np.zeros(3, dtype=np.int64), np.ones(3, dtype=bool))
    state = fast.state()
    assert fast.saved_key_problem(state, seeds) is None
    keys = state["keys"].copy()
    keys[2] ^= np.uint64(1)
    assert fast.saved_key_problem({**state, "keys": keys}, seeds).startswith("keys[2] is ")
    assert fast.saved_key_problem({**state, "keys": keys}, [*seeds[:2], None]) is None  # (never seeded: not judged)
    copies: Any = batched(make_policy("noisy"), 2)  # (the generic path: one copy per environment)
    copies.reset(np.arange(2), seeds[:2])
    saved = copies.state()
    assert copies.saved_key_problem(saved, seeds[:2]) is None
    saved["copies"][1]["key"] ^= 1
    assert copies.saved_key_problem(saved, seeds[:2]).startswith("copies[1].key is ")


def test_a_vector_envs_saved_key_is_judged_against_the_seeds_it_was_reset_with() -> None:
    venv = VectorEnv("coexistence_v0", 2, fixed={"cat_0": "random_walk"})
    venv.reset(seed=[11, 12])
    venv.step(np.zeros((2, 1), dtype=np.int64))
    state = venv.state()
    fresh = VectorEnv("coexistence_v0", 2, fixed={"cat_0": "random_walk"})
    fresh.reset(seed=[11, 12])
    assert fresh.saved_key_problem(state) is None
    state["policies"]["cat_0"]["keys"][1] ^= np.uint64(1)
    assert str(fresh.saved_key_problem(state)).startswith("policies.cat_0.keys[1] is ")
    unseeded = VectorEnv("coexistence_v0", 2, fixed={"cat_0": "random_walk"})
    unseeded.reset()
    assert unseeded.saved_key_problem(state) is None  # (reset without seeds: no key to rederive)


# ---------------------------------------------------------------------------- study files (#10)
STUDY = DOCS / "methods" / "tuning" / "coexistence_v0" / "dqn" / "study.json"
"""A shipped study: DQN's learning_rate on log:0.0001:0.003, survival over the curve."""


def _study_at(tmp_path: Path, forge: Any) -> Path:
    """A copy of :data:`STUDY` under ``tmp_path/study/``, edited by ``forge(document)``; its path."""
    document = json.loads(STUDY.read_text())
    forge(document)
    path = tmp_path / "study" / "study.json"
    path.parent.mkdir()
    path.write_text(json.dumps(document))
    return path


def _setter(*where: Any, value: Any) -> Any:
    def forge(document: dict[str, Any]) -> None:
        table = document
        for key in where[:-1]:
            table = table[key]
        table[where[-1]] = value

    return forge


STUDY_FORGERIES = {
    "label with a line break": (_setter("plan", "label", value="DQN\n| x | y |"), "plan.label"),
    "label with a control character": (_setter("plan", "label", value="DQN\x1b[31m"), "plan.label"),
    "label of megabytes": (_setter("plan", "label", value="D" * 1_000_000), "plan.label"),
    "variant with a |": (_setter("plan", "variant", value="a|b"), "plan.variant"),
    "metric unknown": (_setter("plan", "objective", "metric", value="bogus"), "plan.objective.metric"),
    "over unknown": (_setter("plan", "objective", "over", value="all"), "plan.objective.over"),
    "parameter name with a line break": (
        _setter("plan", "params", value={"learning\nrate": "log:0.0001:0.003"}),
        "plan.params (the key 'learning\\nrate')",  # (every key of a study is printable text)
    ),
    "parameter spec not a range": (_setter("plan", "params", "learning_rate", value="log:x:1e999"), "plan.params.learning_rate"),
    "env steps negative": (_setter("env_steps_trained", value=-5), "env_steps_trained"),
    "env steps past every bound": (_setter("env_steps_trained", value=10**30), "env_steps_trained"),
    "budget a float": (_setter("plan", "budget", "env_steps_at_most", value=1.5), "plan.budget.env_steps_at_most"),
    "trial state unknown": (_setter("trials", 0, "state", value="HACKED"), "trials[0].state"),
    "wall time past ten years": (_setter("trials", 0, "wall_time_s", value=1e12), "trials[0].wall_time_s"),
    "parameter value outside its range": (_setter("trials", 0, "params", "learning_rate", value=0.5), "trials[0].params"),
    "parameter of another plan": (_setter("trials", 1, "params", value={"evil\u202e": 1}), "trials[1].params"),
    "best value outside survival's range": (_setter("best", "value", value=-1.0), "best.value"),
    "best value past a float": (_setter("best", "value", value=10**400), "best.value"),
    "best chosen value a string": (_setter("best", "params", "learning_rate", value="1 | 2"), "best.params.learning_rate"),
    "command with a line break": (_setter("command", value="tune\nrm -rf"), "field command"),
}
"""Each forgery of a study file: ``(how, the field its refusal names)``."""


@pytest.mark.parametrize("name", list(STUDY_FORGERIES))
def test_tuning_summary_refuses_a_forged_study_naming_file_and_field(tmp_path: Path, capsys, name: str) -> None:
    forge, field = STUDY_FORGERIES[name]
    path = _study_at(tmp_path, forge)
    capsys.readouterr()
    assert main(["analyse", "tuning-summary", str(tmp_path)]) == 2
    captured = capsys.readouterr()
    assert not captured.out and captured.err.count("\n") == 1 and str(path) in captured.err and field in captured.err


def test_a_label_holding_a_bar_stays_in_its_cell(tmp_path: Path, capsys) -> None:
    _study_at(tmp_path, _setter("plan", "label", value="DQN | lr"))
    assert main(["analyse", "tuning-summary", str(tmp_path)]) == 0
    header, rule, row = capsys.readouterr().out.strip().splitlines()
    bars = row.replace("\\|", "").count("|")
    assert bars == header.count("|") == rule.count("|") and "DQN \\| lr" in row


# ---------------------------------------------------------------------------- watch's episode cap (#16)
def test_watch_cuts_an_agent_files_long_episode_at_its_cap_and_says_so(tmp_path: Path, capsys, monkeypatch) -> None:
    import argparse

    from agents.empathic_dqn import EmpathicDQN
    from agents.settings import EmpathicDQNSettings
    from empathy_zoo import greedy_episode
    from empathy_zoo.agent_file import write_agent_file
    from empathy_zoo.cli.watch import add_watch
    from empathy_zoo.limits import MAX_CYCLES, MAX_WATCH_STEPS

    venv = VectorEnv("coexistence_v0", 1, fixed={"cat_0": "random_walk"})
    learner = EmpathicDQN([EmpathicDQNSettings(hidden_size=8)], [0], venv.obs_size, venv.num_actions)
    header: dict[str, Any] = {"run_id": "coexistence_v0__dqn-long__s0", "method": "empathic_dqn", "seed": 0}
    header |= {"settings": {"hidden_size": 8}, "env": "coexistence_v0", "fixed": {"cat_0": "stay"}}
    header |= {"env_kwargs": {"max_cycles": MAX_CYCLES}}  # (the most a header may say: 10⁹)
    header["run_id"] = run_id("coexistence_v0", "empathic_dqn", {k: v for k, v in header.items() if k != "run_id"}, 0)
    written = write_agent_file(learner, 0, tmp_path / "long.agent.pt", header)
    assert written is not None
    name = written[0]
    played: list[int | None] = []
    real: Any = greedy_episode.play_greedy

    def counted(*args: Any, max_steps: int | None = None, **kwargs: Any) -> Any:
        played.append(max_steps)
        assert max_steps is not None and max_steps <= MAX_WATCH_STEPS  # (uncapped: a billion steps, never ending)
        return real(*args, max_steps=max_steps, **kwargs)

    monkeypatch.setattr(greedy_episode, "play_greedy", counted)
    parser = argparse.ArgumentParser(prog="empathy-zoo")
    add_watch(parser.add_subparsers(dest="command", required=True))
    args = parser.parse_args(["watch", str(tmp_path / name), "--seed", "3"])
    assert args.handler(args, "empathy-zoo watch") == 0
    lines = capsys.readouterr().out.splitlines()
    assert played == [MAX_WATCH_STEPS]
    note = f"max_cycles {MAX_CYCLES:,} is more than watch plays of an episode ({MAX_WATCH_STEPS:,}"
    assert note in lines[1] and name in lines[1]  # (before the episode's line)
    assert lines[2].startswith(f"episode 0 (seed 3) (its first {MAX_WATCH_STEPS:,} steps): survival {MAX_WATCH_STEPS}")
