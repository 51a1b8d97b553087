"""REPRODUCTION.md verdicts are computed from result files, in both directions."""

from __future__ import annotations

import numpy as np

from empathy_zoo.atomic import write_json_atomic
from empathy_zoo.metrics import METRIC_NAMES
from leaderboard.reproduction import assess_claims, write_reproduction


def _result(env: str, method: str, beta: float, seed: int, **means: float) -> dict:
    rng = np.random.default_rng(seed)
    episodes = 40
    train = {"episode_end_step": list(range(100, 100 * (episodes + 1), 100))}
    for metric in METRIC_NAMES:
        centre = means.get(metric, 0.0)
        train[metric] = (centre + rng.normal(0, 0.01, episodes)).tolist()
    return {
        "schema": 1, "run_id": f"{env}__{method}-{beta}__s{seed}", "env": env, "method": method,
        "method_label": f"{method} {beta}", "seed": seed, "steps": 4000,
        "config": {"settings": {"selfishness": beta}, "variant": env}, "train": train,
        "eval": [{"step": 4000, **{m: [means.get(m, 0.0)] * 3 for m in METRIC_NAMES}}],
    }


def _paper_like(harm_for_low_beta: float) -> list[dict]:
    runs = []
    for seed in range(3):
        for beta, harms, survival in ((1.0, 0.9, 480), (0.75, 0.5, 470), (0.5, 0.0, 460), (0.25, harm_for_low_beta, 455)):
            runs.append(_result("coexistence_v0", "empathic_dqn", beta, seed, harms=harms, survival=survival))
        runs.append(_result("coexistence_v0", "dqn_harm_penalty", 1.0, seed, harms=0.0, survival=470))
        for beta, batteries, eq in ((1.0, 6, 0.5), (0.75, 5, 0.8), (0.5, 4.5, 0.95), (0.25, 3, 0.85)):
            runs.append(_result("sharing_v0", "empathic_dqn", beta, seed, batteries=batteries, equality=eq))
        runs.append(_result("sharing_v0", "dqn_equality", 1.0, seed, batteries=4.5, equality=0.97))
    return runs


def test_claims_that_hold_are_reproduced() -> None:
    claims = assess_claims(_paper_like(harm_for_low_beta=0.0))
    verdicts = {c.text: c.verdict for c in claims}
    assert len(claims) == 7
    assert set(verdicts.values()) == {"reproduced"}, verdicts


def test_a_claim_that_fails_is_reported_as_such(tmp_path) -> None:
    runs = _paper_like(harm_for_low_beta=1.5)  # the least selfish robot harms most
    verdicts = {c.text: c.verdict for c in assess_claims(runs)}
    assert verdicts["Harms to the cat fall as β falls."] == "not reproduced"
    assert verdicts["The less selfish agents eventually survive without harming the cat."] == "not reproduced"
    assert verdicts["Equality peaks at β = 0.5."] == "reproduced"
    for run in runs:
        write_json_atomic(tmp_path / "runs" / f"{run['run_id']}.json", run)
    text = write_reproduction(tmp_path, command="empathy-zoo reproduce --profile test").read_text()
    assert "**not reproduced**" in text and "empathy-zoo reproduce --profile test" in text
