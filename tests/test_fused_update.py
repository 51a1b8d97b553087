"""The compiled update (:mod:`agents.fused_update`): its numbers against float64 autograd and
torch's fused Adam, against the PyTorch update, its exactness (rerun, alone or in an ensemble,
checkpoint), and the fallback to the PyTorch update where numba is missing."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from agents import fused_update
from agents.empathic_dqn import EmpathicDQN, empathic_targets
from agents.settings import EmpathicDQNSettings
from agents.stacked_adam import StackedAdam
from agents.stacked_mlp import init_stacked_mlp

SMALL = {"hidden_size": 32, "replay_capacity": 600, "learning_starts": 32, "target_update_interval": 50}
"""A small learner: 25 inputs, two hidden layers of 32, 5 actions, batches of 32."""


@pytest.fixture
def needs_numba() -> None:
    pytest.importorskip("numba")
    if not fused_update.numba_available():
        pytest.skip(f"numba kernels do not build here: {fused_update.numba_unavailable_reason()}")


def _learner(betas: list[float], kernel: str, seeds: list[int] | None = None, num_others: int = 1, **settings) -> EmpathicDQN:
    """A learner of one run per β whose run with seed ``s`` holds the same 500 transitions in
    any ensemble (drawn from ``s``); ``num_others`` other agents per transition."""
    seeds = list(range(len(betas))) if seeds is None else seeds
    config = [EmpathicDQNSettings(selfishness=b, **{**SMALL, **settings}) for b in betas]
    learner = EmpathicDQN(config, seeds, 25, num_others=num_others, update_kernel=kernel)
    data = [_transitions(seed, num_others) for seed in seeds]
    for i in range(5):
        learner.replay.add(*(np.stack([run[i][field] for run in data]) for field in range(9)))
    return learner


def _transitions(seed: int, others: int) -> list[tuple[np.ndarray, ...]]:
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(5):
        obs, nxt = (rng.integers(-1, 2, size=(100, 25)).astype(np.float32) for _ in range(2))
        swapped = rng.integers(-1, 2, size=(100, others, 25)).astype(np.float32)
        action, reward = rng.integers(0, 5, 100), rng.random(100).astype(np.float32)
        terminated, present = rng.random(100) < 0.05, rng.random((100, others)) < 0.8
        live, unseen = rng.random((100, others)) < 0.95, rng.random((100, others)) < 0.1
        out.append((obs, nxt, swapped, action, reward, terminated, present & live, live, unseen & live & ~present))
    return out


def _close(a: list[torch.Tensor], b: list[torch.Tensor], rel: float) -> list[float]:
    """Largest difference of every tensor pair over the largest magnitude of the first; asserts ``≤ rel``."""
    gaps = [
        float((x - y).abs().max() / x.abs().max()) for x, y in zip((t.detach() for t in a), (t.detach() for t in b), strict=True)
    ]
    assert max(gaps) <= rel, gaps
    return gaps


# ---------------------------------------------------------------------------- hand-made numbers
def test_one_step_on_a_tiny_network_matches_float64_autograd_and_adam(needs_numba: None) -> None:
    """A 3-4-4-2 network, one batch of 5: the loss, its gradient and one Adam step of the kernel
    against autograd and Adam computed by hand in float64."""
    params = init_stacked_mlp([3, 4, 4, 2], [torch.Generator().manual_seed(7)], torch.device("cpu"))
    online = [p.requires_grad_() for p in params]
    target = [p.detach().clone() for p in online]
    optimizer = StackedAdam(online, lr=0.01)
    obs = torch.tensor([[[1.0, 0.0, -1.0], [0.5, 2.0, 0.0], [0.0, 0.0, 1.0], [-1.0, 1.0, 1.0], [2.0, -0.5, 0.25]]])
    action = torch.tensor([[0, 1, 1, 0, 1]])
    y = torch.tensor([[0.3, -0.2, 1.0, 0.0, 0.7]])
    before = [p.detach().double().clone() for p in online]
    fused = fused_update.NumbaUpdate(online, target, optimizer, np.array([0]), 5)
    loss = fused.train(obs, action, y)

    ref = [p[0].clone().requires_grad_() for p in before]
    h = obs[0].double()
    for layer in range(3):
        h = h @ ref[2 * layer] + ref[2 * layer + 1]
        h = torch.relu(h) if layer < 2 else h
    ref_loss = ((h.gather(1, action[0][:, None])[:, 0] - y[0].double()) ** 2).mean()
    ref_loss.backward()
    assert loss == pytest.approx(float(ref_loss.detach()), rel=1e-6)
    for grad, p in zip(fused._grads, ref, strict=True):
        assert p.grad is not None
        np.testing.assert_allclose(grad, p.grad.numpy(), rtol=1e-5, atol=1e-7)
    lr, (b1, b2), eps = 0.01, (0.9, 0.999), 1e-8
    for p, after, m, v in zip(ref, online, optimizer.exp_avg, optimizer.exp_avg_sq, strict=True):
        g = p.grad.detach()
        m_ref, v_ref = (1 - b1) * g, (1 - b2) * g * g
        step = p.detach() - lr / (1 - b1) * m_ref / (v_ref.sqrt() / np.sqrt(1 - b2) + eps)
        np.testing.assert_allclose(m[0].numpy(), m_ref.numpy(), rtol=1e-5, atol=1e-9)
        np.testing.assert_allclose(v[0].numpy(), v_ref.numpy(), rtol=1e-5, atol=1e-12)
        np.testing.assert_allclose(after[0].detach().numpy(), step.numpy(), rtol=1e-6, atol=1e-7)
    assert torch.equal(optimizer.step_count, torch.tensor([1.0]))


@pytest.mark.parametrize("size", [5, 16, 128, 640, 3203])
def test_adam_is_torch_fused_adam_to_float32_rounding(needs_numba: None, size: int) -> None:
    """:func:`agents.fused_update.adam_step` on a run's tensor of ``size`` elements (vectorised
    body and scalar tail) equals ``torch._fused_adam_`` over 30 steps to float32 rounding (on the
    machine it was written on, bit for bit; where torch's build contracts other operations into
    fused multiply-adds, the last bit may differ)."""
    if not hasattr(torch, "_fused_adam_"):
        pytest.skip("this torch has no fused Adam")
    rng = np.random.default_rng(size)
    mine = [torch.from_numpy(rng.standard_normal(size).astype(np.float32)) for _ in range(1)]
    theirs = [t.clone() for t in mine]
    m1, v1, m2, v2 = (torch.zeros(size) for _ in range(4))
    step = torch.zeros(())
    for k in range(1, 31):
        grad = torch.from_numpy((rng.standard_normal(size) * 10.0 ** rng.integers(-6, 1)).astype(np.float32))
        fused_update.adam_step(mine[0].numpy(), grad.numpy(), m1.numpy(), v1.numpy(), float(k), 1e-3)
        step += 1
        torch._fused_adam_(
            theirs, [grad], [m2], [v2], [], [step], lr=1e-3, beta1=0.9, beta2=0.999,
            weight_decay=0.0, eps=1e-8, amsgrad=False, maximize=False,
        )  # fmt: skip
    for a, b in ((mine[0], theirs[0]), (m1, m2), (v1, v2)):
        torch.testing.assert_close(a, b, rtol=2e-6, atol=1e-12)


# ---------------------------------------------------------------------------- against the PyTorch update
CASES = {
    "dqn": ([1.0], {}, 1),
    "empathic": ([0.5], {}, 1),
    "mixed": ([1.0, 0.5, 0.25, 1.0], {}, 1),
    "mean of 2 others": ([0.5, 1.0], {"others": "mean"}, 2),
}


@pytest.mark.parametrize("case", list(CASES))
def test_three_hundred_updates_match_the_torch_update(needs_numba: None, case: str) -> None:
    """After 300 updates every parameter, target and Adam moment of the compiled update is the
    PyTorch update's to 1e-5 of the tensor's largest magnitude (the issue's fallback criterion);
    the step counts are equal."""
    betas, settings, others = CASES[case]
    torch_learner = _learner(betas, "torch", num_others=others, **settings)
    numba_learner = _learner(betas, "numba", num_others=others, **settings)
    assert numba_learner.aggregated == (others > 1)
    assert (torch_learner.update_kernel, numba_learner.update_kernel) == ("torch", "numba")
    for _ in range(300):
        loss_torch, loss_numba = torch_learner.update(), numba_learner.update()
    assert loss_numba == pytest.approx(loss_torch, rel=1e-4)
    _close(torch_learner.online, numba_learner.online, 1e-5)
    _close(torch_learner.target, numba_learner.target, 1e-5)
    _close(torch_learner.optimizer.exp_avg_sq, numba_learner.optimizer.exp_avg_sq, 1e-4)
    assert torch.equal(torch_learner.optimizer._step_table, numba_learner.optimizer._step_table)


def test_every_update_matches_the_torch_update_from_the_same_state(needs_numba: None) -> None:
    """From the PyTorch learner's state at each of 100 updates, one compiled update lands within
    1e-6 of the tensor's largest magnitude of the PyTorch update (no drift to hide a difference)."""
    torch_learner = _learner([1.0, 0.5], "torch")
    numba_learner = _learner([1.0, 0.5], "numba")
    for _ in range(100):
        numba_learner.load_state_dict(torch_learner.state_dict())
        torch_learner.update()
        numba_learner.update()
        _close(torch_learner.online, numba_learner.online, 1e-6)


# ---------------------------------------------------------------------------- exactness
@pytest.mark.parametrize("others", [1, 2])
def test_a_run_is_the_same_alone_or_in_an_ensemble(needs_numba: None, others: int) -> None:
    betas, seeds = [1.0, 0.5, 1.0, 0.25], [11, 12, 13, 14]
    settings = {"others": "mean"} if others > 1 else {}
    ensemble = _learner(betas, "numba", seeds, num_others=others, **settings)
    for _ in range(120):
        ensemble.update()
    for run, (beta, seed) in enumerate(zip(betas, seeds, strict=True)):
        solo = _learner([beta], "numba", [seed], num_others=others, **settings)
        for _ in range(120):
            solo.update()
        heads = [run] + ([len(betas) + [1, 3].index(run)] if beta < 1 else [])
        for mine, alone in zip(ensemble.online, solo.online, strict=True):
            assert torch.equal(mine[heads], alone)
        for mine, alone in zip(
            ensemble.optimizer.exp_avg + ensemble.optimizer.exp_avg_sq,
            solo.optimizer.exp_avg + solo.optimizer.exp_avg_sq,
            strict=True,
        ):
            assert torch.equal(mine[heads], alone)


def test_a_rerun_is_identical(needs_numba: None) -> None:
    first, second = _learner([0.5, 1.0], "numba"), _learner([0.5, 1.0], "numba")
    losses = [(first.update(), second.update()) for _ in range(80)]
    assert all(a == b for a, b in losses)
    for a, b in zip(first.online + first.target, second.online + second.target, strict=True):
        assert torch.equal(a, b)


def test_a_checkpoint_continues_identically(needs_numba: None) -> None:
    """state_dict after 70 updates, loaded into a fresh learner, continues exactly as the
    uninterrupted one (a target copy at 100 in between)."""
    uninterrupted = _learner([0.5, 1.0], "numba")
    for _ in range(70):
        uninterrupted.update()
    state = uninterrupted.state_dict()
    resumed = _learner([0.5, 1.0], "numba")
    resumed.load_state_dict(state)
    for _ in range(60):
        assert uninterrupted.update() == resumed.update()
    for a, b in zip(uninterrupted.state_dict()["online"], resumed.state_dict()["online"], strict=True):
        assert torch.equal(a, b)
    for name in ("exp_avg", "exp_avg_sq"):
        for a, b in zip(uninterrupted.optimizer.state_dict()[name], resumed.optimizer.state_dict()[name], strict=True):
            assert torch.equal(a, b)
    assert torch.equal(uninterrupted.optimizer._step_table, resumed.optimizer._step_table)


# ---------------------------------------------------------------------------- the batch, the targets, one call
@pytest.mark.parametrize("size", [1, 37, 600])
def test_the_compiled_indices_are_sample_indices(needs_numba: None, size: int) -> None:
    """:func:`agents.fused_update.draw_indices` draws the numbers of
    :meth:`EmpathicDQN.sample_indices` (the replay-sampling stream), at every gradient step."""
    learner = _learner([0.5, 1.0, 0.25], "numba", seeds=[3, 99, 2**40])
    learner.replay.size = size
    for grad_steps in (0, 1, 17, 10**6, 2**40):
        learner.grad_steps = grad_steps
        drawn = fused_update.draw_indices(learner._sample_keys[:, 0], grad_steps * 32, size, 32)
        np.testing.assert_array_equal(drawn, learner.sample_indices().numpy())
        assert drawn.dtype == np.int64 and drawn.min() >= 0 and drawn.max() < size


@pytest.mark.parametrize("others", [1, 3])
def test_the_compiled_gather_is_sample_batch_bit_for_bit(needs_numba: None, others: int) -> None:
    """The compiled gather and decode of :meth:`NumbaUpdate.sample_batch` (and
    :func:`agents.fused_update.gather` of the replay's own layout) return what
    :meth:`EmpathicDQN.sample_batch` (and :meth:`StackedReplay.sample`) return on the same
    indices: the same keys, dtypes, shapes and values, bit for bit, for the closest other agent
    and for three aggregated by their mean (every code of an other agent occurs)."""
    learner = _learner([0.5, 1.0], "numba", num_others=others, **({"others": "mean"} if others > 1 else {}))
    assert learner.aggregated == (others > 1)
    for grad_steps in (0, 5, 123):
        learner.grad_steps = grad_steps
        index = learner.sample_indices()
        assert learner._numba is not None
        pairs = [
            (learner._numba.sample_batch(learner.replay, index, learner.aggregated), learner.sample_batch(index)),
            (fused_update.gather(learner.replay, index), learner.replay.sample(index)),
        ]
        for mine, theirs in pairs:
            assert mine.keys() == theirs.keys()
            for name, value in theirs.items():
                assert mine[name].dtype == value.dtype and mine[name].shape == value.shape, name
                assert torch.equal(mine[name], value), name
    codes = learner.replay.flags[:, : learner.replay.size, 2:].unique().tolist()
    assert codes == [0, 1, 2, 3]
    with pytest.raises(IndexError, match="outside the memory"):
        fused_update.gather(learner.replay, torch.full((2, 4), 600))


def _random_target_inputs(seed: int, others: int, k: int = 3, b: int = 64, a: int = 5) -> dict[str, torch.Tensor]:
    """Random values (some actions tied) and masks in every combination a replay holds."""
    g = torch.Generator().manual_seed(seed)
    values = [torch.randn((k, b, a), generator=g) * 3 for _ in range(2)]
    values[0][:, ::7, 1] = values[0][:, ::7, 3]  # (ties: the first one is taken)
    live = torch.rand((k, b, others), generator=g) < 0.8
    present = live & (torch.rand((k, b, others), generator=g) < 0.7)
    unseen = live & ~present & (torch.rand((k, b, others), generator=g) < 0.5)
    return {
        "reward": torch.randn((k, b), generator=g),
        "terminated": torch.rand((k, b), generator=g) < 0.2,
        "q_next": values[0],
        "target_next": values[1],
        "target_swapped": torch.randn((k, b, others, a), generator=g) * 3,
        "present": present,
        "live": live,
        "unseen": unseen,
        "selfishness": torch.tensor([[0.5], [0.25], [1.0]])[:k],
    }


@pytest.mark.parametrize("rule, others", [("closest", 1), ("mean", 2), ("mean", 3), ("mean", 5), ("min", 3)])
@pytest.mark.parametrize("seed", [0, 1])
def test_the_compiled_targets_are_the_torch_targets(needs_numba: None, rule: str, others: int, seed: int) -> None:
    """:func:`agents.fused_update.empathic_targets` equals :func:`agents.empathic_dqn.empathic_targets`
    on random inputs (unseen, present and live masks, terminated transitions, tied actions): bit
    for bit, except the mean of five others, to float32 rounding (the compiled sum is taken in
    order; torch's over five is not, over two to four it is)."""
    x = _random_target_inputs(seed, others)
    if rule == "closest":
        for name in ("target_swapped", "present", "live", "unseen"):
            x[name] = x[name][:, :, 0]
    live = None if rule == "closest" else x["live"]
    args = (x["reward"], x["terminated"], x["q_next"], x["target_next"], x["target_swapped"], x["present"], 0.99)
    y, y_emp = empathic_targets(*args, x["selfishness"], rule, live, x["unseen"])
    mine = fused_update.empathic_targets(
        *(t.numpy() for t in args[:-1]), 0.99, x["selfishness"].numpy(), rule, None if live is None else live.numpy(),
        x["unseen"].numpy(),
    )  # fmt: skip
    assert mine[0].dtype == mine[1].dtype == np.float32
    np.testing.assert_array_equal(mine[0], y.numpy())
    if others == 5:
        np.testing.assert_allclose(mine[1], y_emp.numpy(), rtol=1e-6, atol=1e-6)
    else:
        np.testing.assert_array_equal(mine[1], y_emp.numpy())


def test_the_compiled_targets_on_hand_made_numbers(needs_numba: None) -> None:
    """One run, β = 0.5, γ = 0.5, two others, four transitions by hand (the mean and the least
    of the others that count; unseen ones count for nothing; all unseen: the robot's own
    continuation in their place, ``y_emp = y − (1 − β)·r``)."""
    q_next = np.array([[[0, 1], [2, 2], [5, 0], [0, 1]]], np.float32)  # argmax: 1, 0 (tie), 0, 1
    target_next = np.array([[[10, 20], [30, 40], [50, 60], [70, 80]]], np.float32)
    swapped = np.array([[[[4, 2], [8, 6]]] * 4], np.float32)  # maxima 4 and 8
    reward = np.array([[1, 2, 3, 4]], np.float32)
    terminated = np.array([[False, False, True, False]])
    present = np.array([[[True, True], [True, False], [False, False], [True, True]]])
    live = np.array([[[True, True], [True, True], [True, False], [True, True]]])
    unseen = np.array([[[False, False], [False, False], [True, False], [False, True]]])
    y_expected = [1 + 0.5 * 20, 2 + 0.5 * 30, 3, 4 + 0.5 * 80]
    for rule, others in (("mean", [(2 + 4) / 2, (2 + 0) / 2, None, 2]), ("min", [2, 0, None, 2])):
        y, y_emp = fused_update.empathic_targets(
            reward, terminated, q_next, target_next, swapped, present, 0.5, np.array([0.5]), rule, live, unseen
        )
        np.testing.assert_array_equal(y[0], y_expected)
        expected = [
            y_expected[i] - 0.5 * reward[0, i] if o is None else 0.5 * y_expected[i] + 0.5 * o for i, o in enumerate(others)
        ]
        np.testing.assert_array_equal(y_emp[0], expected)
    y, y_emp = fused_update.empathic_targets(
        reward, terminated, q_next, target_next, swapped[:, :, 0], present[:, :, 0], 0.5, np.array([0.5]), "closest",
        None, unseen[:, :, 0],
    )  # fmt: skip
    np.testing.assert_array_equal(y_emp[0], [0.5 * y_expected[0] + 1, 0.5 * y_expected[1] + 1, 0.5 * y_expected[2], 0.5 * 44 + 1])
    with pytest.raises(ValueError, match="others must be one of"):
        fused_update.empathic_targets(reward, terminated, q_next, target_next, swapped, present, 0.5, np.ones(1), "max")


ONE_CALL_CASES = {
    "empathic": ([0.5], {}, 1),
    "mixed": ([1.0, 0.5, 0.25, 1.0], {}, 1),
    "dqn": ([1.0, 1.0], {}, 1),
    "mean of 2 others": ([0.5, 1.0], {"others": "mean"}, 2),
    "least of 3 others": ([0.25, 0.5], {"others": "min"}, 3),
}


@pytest.mark.parametrize("case", list(ONE_CALL_CASES))
def test_the_one_call_update_is_the_step_with_torch_targets(needs_numba: None, case: str) -> None:
    """The whole update in one compiled call (indices, gather, next values, the compiled targets,
    train step) computes bit for bit what the compiled passes with :meth:`EmpathicDQN.targets`
    in torch in between compute, over 150 updates (a target copy at 50, 100 and 150)."""
    betas, settings, others = ONE_CALL_CASES[case]
    whole, split = (_learner(betas, "numba", num_others=others, **settings) for _ in range(2))
    assert not any(map(whole._overridden, ("targets", "other_inputs", "sample_batch", "sample_indices")))
    split.targets = split.targets  # type: ignore[method-assign]  # (set on the instance: the split path, same targets)
    assert split._overridden("targets")
    for _ in range(150):
        assert whole.update() == split.update()
    for a, b in zip(
        whole.online + whole.target + whole.optimizer.exp_avg, split.online + split.target + split.optimizer.exp_avg, strict=True
    ):
        assert torch.equal(a, b)


class _OwnIndices(EmpathicDQN):
    """Draws its batches as Empathic DQN does, through an overridden :meth:`sample_indices`."""

    def sample_indices(self) -> torch.Tensor:
        return super().sample_indices()


class _CountedTargets(EmpathicDQN):
    """Empathic DQN's targets through an override that counts its calls."""

    calls = 0

    def targets(self, batch, q_next, target_next, target_swapped):  # type: ignore[no-untyped-def]
        type(self).calls += 1
        return super().targets(batch, q_next, target_next, target_swapped)


def test_overridden_indices_and_targets_are_used(needs_numba: None) -> None:
    """An overridden :meth:`sample_indices` is asked for the batch (the one call then takes its
    indices); an overridden :meth:`targets` is called at every update (no compiled targets), and
    both give the default learner's numbers."""
    _CountedTargets.calls = 0
    reference = _learner([0.5], "numba")
    config = [EmpathicDQNSettings(selfishness=0.5, **SMALL)]
    learners = [cls(config, [0], 25, update_kernel="numba") for cls in (_OwnIndices, _CountedTargets)]
    for learner in learners:
        learner.replay.load_state_dict(reference.replay.state_dict())
    assert [learners[0]._overridden(name) for name in ("targets", "sample_indices")] == [False, True]
    assert learners[1]._overridden("targets")
    for _ in range(60):
        loss = reference.update()
        assert [learner.update() for learner in learners] == [loss, loss]
    assert _CountedTargets.calls == 60
    for learner in learners:
        for a, b in zip(reference.online, learner.online, strict=True):
            assert torch.equal(a, b)


def test_the_silver_rule_keeps_its_targets_and_matches_torch(needs_numba: None) -> None:
    """A plug-in that overrides :meth:`targets` (the silver rule) trains with the compiled passes
    and its own torch targets: from the PyTorch learner's state at each of 100 updates, one
    compiled update lands within 1e-6 of the tensor's largest magnitude of the PyTorch update
    (over hundreds of updates its kink, ``max(c − o, 0)``, lets rounding differences grow)."""
    from baselines.silver_rule import SilverRuleDQN

    config = [EmpathicDQNSettings(selfishness=b, **SMALL) for b in (0.5, 1.0)]
    pair = [SilverRuleDQN(config, [0, 1], 25, update_kernel=kernel) for kernel in ("torch", "numba")]
    reference = _learner([0.5, 1.0], "torch")
    for learner in pair:
        learner.replay.load_state_dict(reference.replay.state_dict())
    assert pair[1].update_kernel == "numba" and pair[1]._overridden("targets")
    for _ in range(100):
        pair[1].load_state_dict(pair[0].state_dict())
        losses = [learner.update() for learner in pair]
        assert losses[1] == pytest.approx(losses[0], rel=1e-5)
        _close(pair[0].online, pair[1].online, 1e-6)


# ---------------------------------------------------------------------------- fallback
def test_without_numba_the_learner_says_so_and_trains_with_torch(monkeypatch: pytest.MonkeyPatch) -> None:
    """Asked for the numba kernel where it cannot build, the learner warns, reports ``torch`` and
    trains exactly as the PyTorch update."""
    monkeypatch.setattr(fused_update, "numba_available", lambda: False)
    monkeypatch.setattr(fused_update, "numba_unavailable_reason", lambda: "numba is not installed (test)")
    with pytest.warns(RuntimeWarning, match="numba update kernel is not available.*numba is not installed"):
        fallen = _learner([0.5], "numba")
    assert fallen.update_kernel == "torch"
    reference = _learner([0.5], "torch")
    for _ in range(20):
        assert fallen.update() == reference.update()
    for a, b in zip(fallen.online, reference.online, strict=True):
        assert torch.equal(a, b)


def test_the_default_kernel_is_auto_and_a_bad_name_is_refused() -> None:
    assert EmpathicDQN.update_kernel == "auto"
    expected = "numba" if fused_update.numba_available() else "torch"
    assert _learner([1.0], None).update_kernel == expected  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="update_kernel must be one of 'auto', 'numba', 'torch', got 'numpy'"):
        _learner([1.0], "numpy")


def test_auto_is_numba_where_it_builds_and_torch_with_a_warning_where_not(monkeypatch: pytest.MonkeyPatch) -> None:
    """``auto`` resolves to the compiled kernel where numba builds; where it does not, the learner
    says so (its results differ in their last bits) and trains exactly as the PyTorch update."""
    if fused_update.numba_available():
        assert EmpathicDQN.resolved_update_kernel("auto", "cpu") == "numba"
        assert _learner([0.5], "auto").update_kernel == "numba"
    monkeypatch.setattr(fused_update, "numba_available", lambda: False)
    monkeypatch.setattr(fused_update, "numba_unavailable_reason", lambda: "numba is not installed (test)")
    assert EmpathicDQN.resolved_update_kernel("auto", "cpu") == "torch"
    with pytest.warns(RuntimeWarning, match="not available .*numba is not installed.*last bits"):
        fallen = _learner([0.5], "auto")
    assert fallen.update_kernel == "torch"


def test_numba_is_refused_off_the_cpu_and_auto_is_torch_there() -> None:
    with pytest.raises(ValueError, match="numba update kernel runs on the CPU only; on meta"):
        EmpathicDQN.resolved_update_kernel("numba", "meta")
    assert EmpathicDQN.resolved_update_kernel("auto", "meta") == "torch"
    assert EmpathicDQN.resolved_update_kernel("torch", "cpu") == "torch"


@pytest.mark.parametrize("ta, tb", [(False, False), (True, False), (False, True)])
def test_the_loop_products_equal_the_blas_ones(needs_numba: None, ta: bool, tb: bool) -> None:
    """:func:`agents.fused_update.gemm` in its own loops (where torch carries no BLAS) and by
    BLAS agree to float32 rounding, on a strided input as the replay's views are."""
    rng = np.random.default_rng(3)
    a = rng.standard_normal((40, 3, 32)).astype(np.float32)[:, 1]  # (40, 32), rows 96 floats apart
    a[a < 0] = 0  # (zeros, as ReLU leaves them)
    a = a.T.copy() if ta else a
    b = rng.standard_normal((32, 24)).astype(np.float32)
    b = b.T.copy() if tb else b
    loops, blas = np.zeros((40, 24), np.float32), np.zeros((40, 24), np.float32)
    fused_update.gemm(ta, tb, a, b, loops, False)
    fused_update.gemm(ta, tb, a, b, blas, fused_update.BLAS)
    exact = (a.T if ta else a).astype(np.float64) @ (b.T if tb else b).astype(np.float64)
    np.testing.assert_allclose(loops, exact, rtol=1e-5, atol=1e-5)
    np.testing.assert_allclose(blas, exact, rtol=1e-5, atol=1e-5)


def test_without_blas_the_loops_match_the_torch_update(needs_numba: None, monkeypatch: pytest.MonkeyPatch) -> None:
    """The kernels' own loops (where torch exports no ``sgemm``): 300 updates of a mixed
    ensemble equal the PyTorch update to 1e-5 of each tensor's largest magnitude."""
    monkeypatch.setattr(fused_update, "BLAS", False)
    torch_learner, numba_learner = _learner([1.0, 0.5], "torch"), _learner([1.0, 0.5], "numba")
    for _ in range(300):
        torch_learner.update()
        numba_learner.update()
    _close(torch_learner.online, numba_learner.online, 1e-5)
