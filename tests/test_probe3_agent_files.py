"""Agent files and checkpoints from a hostile user: zip bombs, unknown keys and members, SB3 sizes.

Every forgery is made in ``tmp_path`` from a genuine file the suite's own code wrote: an
``.agent.pt`` (:func:`~empathy_zoo.agent_file.write_agent_file`), a Stable-Baselines3
``.agent.zip`` (the SB3 learner's ``save_agent``) and a checkpoint (:func:`save_checkpoint`, and an
ensemble's, killed after it). A bomb declares a huge size in the zip's central directory, or is a
few MiB of zeros deflated: nothing here allocates gigabytes. Each is refused with one
``ValueError`` line naming the file, before ``torch.load`` or SB3's ``load`` reads it.
"""

from __future__ import annotations

import io
import json
import struct
import zipfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import torch
from test_checkpoint_forgeries import assert_refused, checkpointed, forged  # noqa: F401 (a fixture)

from empathy_zoo import load_agent
from empathy_zoo.agent_file import AgentFileError, file_sha256, write_agent_file
from empathy_zoo.run_ids import run_id
from empathy_zoo.safe_data import zip_members
from empathy_zoo.training.checkpoint import CheckpointError, check_checkpoint_keys, load_checkpoint, save_checkpoint

FIELDS = {
    "method": "empathic_dqn",
    "env": "coexistence_v0",
    "settings": {"hidden_size": 8},
    "env_kwargs": {"max_cycles": 60},
    "seed": 0,
}
HEADER = {"run_id": run_id("coexistence_v0", "empathic_dqn", FIELDS, 0), **FIELDS}
"""A header as the trainer writes one: its run id the one its fields give."""
ZEROS = 8 << 20
"""Bytes of zeros a real bomb deflates (8 MiB: a few KiB in the file)."""


class Plain:
    """A learner offering its agent as plain tensors (two layers of a seeded random MLP)."""

    def agent_state(self, run: int) -> dict[str, Any]:
        rng = np.random.default_rng(3)
        layers = [rng.standard_normal(shape).astype(np.float32) for shape in ((25, 8), (8,), (8, 5), (5,))]
        return {"heads": {"q": layers}, "acting": "q"}


def members_of(data: bytes) -> dict[str, bytes]:
    with zipfile.ZipFile(io.BytesIO(data)) as archive:
        return {name: archive.read(name) for name in archive.namelist()}


def zip_of(members: dict[str, bytes], deflated: Callable[[str], bool] = lambda name: False) -> bytes:
    """A zip of ``members``, those ``deflated`` names deflated, the others stored."""
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w") as archive:
        for name, data in members.items():
            archive.writestr(name, data, zipfile.ZIP_DEFLATED if deflated(name) else zipfile.ZIP_STORED)
    return buffer.getvalue()


def declared(data: bytes, name: str, size: int, compressed: bool = False) -> bytes:
    """``data`` (a zip) whose central directory says member ``name`` is ``size`` bytes once read
    (and in the file too, where ``compressed``): the member itself is unchanged."""
    data = bytearray(data)
    at = data.find(b"PK\x01\x02")
    while at >= 0:
        length = struct.unpack_from("<H", data, at + 28)[0]
        if bytes(data[at + 46 : at + 46 + length]).decode() == name:
            struct.pack_into("<L", data, at + 24, size)
            if compressed:
                struct.pack_into("<L", data, at + 20, size)
            return bytes(data)
        at = data.find(b"PK\x01\x02", at + 4)
    raise AssertionError(f"no member {name}")


def unreached(*args: Any, **kwargs: Any) -> Any:
    raise AssertionError("the file was read before it was checked")


# ---------------------------------------------------------------------------- the torch agent file
@pytest.fixture(scope="module")
def agent_pt(tmp_path_factory: pytest.TempPathFactory) -> bytes:
    path = tmp_path_factory.mktemp("agent") / "r.agent.pt"
    assert write_agent_file(Plain(), 0, path, HEADER) == ("r.agent.pt", file_sha256(path))
    return path.read_bytes()


def _bomb(data: bytes) -> bytes:
    members = members_of(data)
    folder = next(iter(members)).split("/")[0]
    return zip_of({**members, f"{folder}/data/99": bytes(ZEROS)}, lambda name: name.endswith("/99"))


def _huge_record(data: bytes) -> bytes:
    name = next(name for name in members_of(data) if name.endswith("/data/0"))
    return declared(data, name, 3 << 30, compressed=True)


ZIP_FORGERIES: dict[str, tuple[Callable[[bytes], bytes], str]] = {
    "every record deflated": (lambda data: zip_of(members_of(data), lambda name: True), "is not stored as it is"),
    "8 MiB of zeros deflated": (_bomb, r"data/99' is not stored as it is"),
    "a record declaring 3 GiB": (_huge_record, "more than the .* bytes of the file"),
}
"""The forgeries of a ``torch.save`` zip that an agent file and a checkpoint both refuse."""

TORCH_FORGERIES: dict[str, tuple[Callable[[bytes], bytes], str]] = {
    **ZIP_FORGERIES,
    "a record no torch.save writes": (
        lambda data: zip_of({**members_of(data), "archive/notes.txt": b"hello"}),
        "'archive/notes.txt', which is no record torch.save writes",
    ),
    "5,000 records": (
        lambda data: zip_of({**members_of(data), **{f"archive/data/{i + 10}": b"" for i in range(5000)}}),
        "at most 4,096 members",
    ),
    "no zip (torch's legacy format)": (
        lambda data: _legacy(torch.load(io.BytesIO(data), weights_only=True)),
        "it is no zip archive",
    ),
}


def _legacy(document: dict[str, Any]) -> bytes:
    buffer = io.BytesIO()
    torch.save(document, buffer, _use_new_zipfile_serialization=False)
    return buffer.getvalue()


@pytest.mark.parametrize("forgery", list(TORCH_FORGERIES))
def test_a_forged_torch_agent_zip_is_refused_before_torch_reads_it(agent_pt, tmp_path, monkeypatch, forgery) -> None:
    genuine = tmp_path / "genuine.agent.pt"
    genuine.write_bytes(agent_pt)
    assert load_agent(genuine).act(np.zeros(25, np.float32)) in range(5)
    change, message = TORCH_FORGERIES[forgery]
    path = tmp_path / "r.agent.pt"
    path.write_bytes(change(agent_pt))
    assert path.stat().st_size < 1 << 20
    monkeypatch.setattr(torch, "load", unreached)
    with pytest.raises(AgentFileError, match=rf"^{path} is not an empathy-zoo agent file \(.*{message}") as refused:
        load_agent(path)
    assert "\n" not in str(refused.value)


def test_a_torch_agent_with_a_key_no_agent_file_has_is_refused(agent_pt, tmp_path) -> None:
    document = torch.load(io.BytesIO(agent_pt), weights_only=True)
    path = tmp_path / "r.agent.pt"
    torch.save({**document, "replay": torch.zeros(4)}, path)
    with pytest.raises(AgentFileError, match=rf"^agent file {path}: its agent file holds a key 'replay', which no agent file"):
        load_agent(path)


# ---------------------------------------------------------------------------- the SB3 agent file
@pytest.fixture(scope="module")
def sb3_agents(tmp_path_factory: pytest.TempPathFactory) -> dict[str, bytes]:
    """A genuine ``.agent.zip`` of SB3's DQN and PPO each (as built, untrained), by algorithm."""
    pytest.importorskip("stable_baselines3")
    from baselines.sb3 import SB3Learner, SB3Settings
    from empathy_zoo.vector import VectorEnv

    out = tmp_path_factory.mktemp("sb3")
    small = {"dqn": {"buffer_size": 1_000, "learning_starts": 50}, "ppo": {"n_steps": 64, "n_epochs": 2}}
    files = {}
    for algorithm, kwargs in small.items():
        venv = VectorEnv("coexistence_v0", 1, fixed={"cat_0": "random_walk"}, max_cycles=60)
        learner = SB3Learner([SB3Settings(algorithm=algorithm, algorithm_kwargs=kwargs)], [0], venv.obs_size, venv.num_actions)
        head = {"method": f"sb3_{algorithm}", "settings": {"algorithm": algorithm}, "env": "coexistence_v0", "env_kwargs": {}}
        written = write_agent_file(learner, 0, out / f"{algorithm}.agent.pt", head)
        assert written is not None
        files[algorithm] = (out / written[0]).read_bytes()
    return files


def _with(member: str, change: Callable[[Any], Any]) -> Callable[[bytes], bytes]:
    """A forgery: the JSON member ``member`` of an SB3 agent replaced by ``change(it)``."""

    def forge(data: bytes) -> bytes:
        members = members_of(data)
        members[member] = json.dumps(change(json.loads(members[member]))).encode()
        return zip_of(members)

    return forge


def _pth(name: str, document: Any = None, deflated: bool = False) -> Callable[[bytes], bytes]:
    """A forgery: the ``.pth`` member ``name`` written anew of ``document`` (``None``: its own), its
    records deflated where ``deflated``."""

    def forge(data: bytes) -> bytes:
        members = members_of(data)
        inner = members[name]
        if document is not None:
            buffer = io.BytesIO()
            torch.save(document, buffer)
            inner = buffer.getvalue()
        if deflated:
            inner = zip_of(members_of(inner), lambda record: True)
        return zip_of({**members, name: inner})

    return forge


def _declared_huge(data: bytes) -> bytes:
    """Two members deflated, each declaring 3 GiB once expanded (6 GiB: more than an agent file's 4)."""
    data = zip_of(members_of(data), lambda name: name in ("system_info.txt", "_stable_baselines3_version"))
    return declared(declared(data, "system_info.txt", 3 << 30), "_stable_baselines3_version", 3 << 30)


def _data(**changes: Any) -> Callable[[bytes], bytes]:
    return _with("data", lambda data: {**data, **changes})


def _arch(arch: Any) -> Callable[[bytes], bytes]:
    return _with("data", lambda data: {**data, "policy_kwargs": {**data["policy_kwargs"], "net_arch": arch}})


SB3_FORGERIES: dict[str, tuple[str, Callable[[bytes], bytes], str]] = {
    "members declaring 6 GiB": ("dqn", _declared_huge, "its members expand to [0-9,]+ bytes, more than the 4,294,967,296"),
    "a member SB3 does not write": (
        "dqn",
        lambda data: zip_of({**members_of(data), "extra.bin": b"\0" * 16}),
        "holds a member 'extra.bin', which no agent file",
    ),
    "a member bzip2-compressed": (
        "ppo",
        lambda data: _recompressed(data, "system_info.txt", zipfile.ZIP_BZIP2),
        "system_info.txt is compressed with method 12",
    ),
    "a key of its own member unknown": (
        "dqn",
        _with("empathy_zoo_agent.json", lambda member: {**member, "surprise": 1}),
        "its empathy_zoo_agent.json holds a key 'surprise', which no agent file has",
    ),
    "a key of data SB3 does not write": ("dqn", _data(surprise=1), "field data.surprise: expected none"),
    "policy.pth of deflated records": (
        "dqn",
        _pth("policy.pth", deflated=True),
        "its member policy.pth is no archive of torch.save .*is not stored as it is",
    ),
    "a variable set over the policy's weights": (
        "dqn",
        _pth("pytorch_variables.pth", {"policy.q_net.q_net.0.weight": torch.zeros(2, 2)}),
        "pytorch_variables.pth holds 'policy.q_net.q_net.0.weight'; DQN and PPO keep no variables",
    ),
    "variables of a tensor": (
        "ppo",
        _pth("pytorch_variables.pth", torch.zeros(2)),
        "pytorch_variables.pth holds Tensor; DQN and PPO keep no variables",
    ),
    "a layer 2**40 wide": ("dqn", _arch([2**40]), r"field data.policy_kwargs.net_arch\[0\]: expected an int >= 1 and <= 524,288"),
    "65 layers": ("dqn", _arch([1] * 65), "field data.policy_kwargs.net_arch: expected a list of at most 64 layer widths"),
    "more weights than the file holds": ("dqn", _arch([2048, 2048]), "net_arch: expected networks the file holds"),
    "PPO's net_arch of a third network": ("ppo", _arch({"pi": [8], "vf": [8], "qf": [8]}), "net_arch: expected"),
    "a policy_kwargs key unknown": (
        "ppo",
        _with("data", lambda data: {**data, "policy_kwargs": {**data["policy_kwargs"], "features_dim": 10**9}}),
        "field data.policy_kwargs.features_dim",
    ),
    "n_steps 10**12": ("ppo", _data(n_steps=10**12), "field data.n_steps: expected an int >= 1 and <= 1,000,000,000"),
    "n_envs 10**12": ("dqn", _data(n_envs=10**12), "field data.n_envs: expected an int >= 1 and <= 1,000,000"),
    "buffer_size 0": ("dqn", _data(buffer_size=0), "field data.buffer_size"),
    "batch_size 0": ("ppo", _data(batch_size=0), "field data.batch_size"),
    "seed 2**40": ("dqn", _data(seed=2**40), "field data.seed"),
    "use_sde": ("ppo", _data(use_sde=True), "field data.use_sde"),
}


def _recompressed(data: bytes, name: str, method: int) -> bytes:
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w") as archive:
        for member, content in members_of(data).items():
            archive.writestr(member, content, method if member == name else zipfile.ZIP_STORED)
    return buffer.getvalue()


@pytest.mark.parametrize("forgery", list(SB3_FORGERIES))
def test_a_forged_sb3_agent_is_refused_before_sb3_loads_it(sb3_agents, tmp_path, monkeypatch, forgery) -> None:
    import stable_baselines3

    algorithm, change, message = SB3_FORGERIES[forgery]
    path = tmp_path / "r.agent.zip"
    path.write_bytes(change(sb3_agents[algorithm]))
    assert path.stat().st_size < 1 << 20
    cls = getattr(stable_baselines3, algorithm.upper())
    monkeypatch.setattr(cls, "load", unreached)
    with pytest.raises(AgentFileError, match=rf"^(agent file )?{path}\b.*{message}") as refused:
        load_agent(path)
    assert "\n" not in str(refused.value)


@pytest.mark.parametrize("algorithm, arch", [("dqn", [8]), ("dqn", [128, 128, 8]), ("ppo", {"pi": [8], "vf": [8]})])
def test_an_sb3_agent_whose_net_arch_is_not_its_weights_is_refused_in_one_line(sb3_agents, tmp_path, algorithm, arch) -> None:
    """A ``net_arch`` within its bounds but not the networks the file's weights are: SB3 builds the
    stated networks (their size bounded by the file's) and its strict weight load refuses them."""
    path = tmp_path / "r.agent.zip"
    path.write_bytes(_arch(arch)(sb3_agents[algorithm]))
    refusal = rf"^agent file {path}: stable_baselines3 cannot load it \(RuntimeError: Error\(s\) in loading state_dict"
    with pytest.raises(AgentFileError, match=refusal) as refused:
        load_agent(path)
    assert "\n" not in str(refused.value)
    genuine = tmp_path / "genuine.agent.zip"
    genuine.write_bytes(sb3_agents[algorithm])
    load_agent(genuine)  # (the same file with its own net_arch loads)


def test_nothing_of_an_sb3_agent_is_decompressed_before_its_directory_is_checked(sb3_agents, tmp_path, monkeypatch) -> None:
    path = tmp_path / "r.agent.zip"
    path.write_bytes(_declared_huge(sb3_agents["dqn"]))
    monkeypatch.setattr(zipfile.ZipFile, "open", unreached)
    with pytest.raises(AgentFileError, match="more than the 4,294,967,296 bytes an agent file may hold"):
        load_agent(path)


@pytest.mark.parametrize("algorithm", ["dqn", "ppo"])
def test_a_loaded_sb3_agent_builds_buffers_of_one_step_whatever_its_data_says(sb3_agents, tmp_path, algorithm) -> None:
    path = tmp_path / "r.agent.zip"
    sizes = {"dqn": {"buffer_size": 100_000, "n_envs": 16}, "ppo": {"n_steps": 100_000, "n_envs": 16}}
    path.write_bytes(_data(**sizes[algorithm])(sb3_agents[algorithm]))
    model = load_agent(path).model
    buffer = model.replay_buffer if algorithm == "dqn" else model.rollout_buffer
    assert buffer.observations.nbytes <= 25 * 4, buffer.observations.shape


# ---------------------------------------------------------------------------- checkpoints
@pytest.fixture
def saved(tmp_path: Path) -> bytes:
    path = tmp_path / "genuine.pt"
    save_checkpoint(path, {"run_ids": ["a"], "learner": {"online": [torch.ones(3, 2)]}})
    return path.read_bytes()


CHECKPOINT_FORGERIES: dict[str, tuple[Callable[[bytes], bytes], str]] = {
    **ZIP_FORGERIES,
    "a record no torch.save writes": (
        lambda data: zip_of({**members_of(data), "archive/run.sh": b"echo"}),
        "'archive/run.sh', which is no record torch.save writes",
    ),
    "no zip (torch's legacy format)": (
        lambda data: _legacy(torch.load(io.BytesIO(data), weights_only=True)),
        "it is no zip archive",
    ),
}


@pytest.mark.parametrize("forgery", list(CHECKPOINT_FORGERIES))
def test_a_forged_checkpoint_zip_is_refused_before_torch_reads_it(saved, tmp_path, monkeypatch, forgery) -> None:
    change, message = CHECKPOINT_FORGERIES[forgery]
    path = tmp_path / "c.pt"
    path.write_bytes(change(saved))
    monkeypatch.setattr(torch, "load", unreached)
    with pytest.raises(CheckpointError, match=rf"^checkpoint {path} is corrupted or unreadable \(.*{message}") as refused:
        load_checkpoint(path)
    assert "\n" not in str(refused.value)


def test_a_checkpoint_with_a_key_it_was_not_asked_for_is_refused(tmp_path) -> None:
    path = tmp_path / "c.pt"
    save_checkpoint(path, {"run_ids": ["a"], "surprise": 1})
    payload = load_checkpoint(path)
    with pytest.raises(CheckpointError, match=rf"^checkpoint {path} is corrupted .*it holds a key 'surprise'"):
        check_checkpoint_keys(path, payload, {"run_ids": list})


def test_an_ensembles_checkpoint_with_a_key_of_its_own_is_refused_naming_it(checkpointed, tmp_path, capsys) -> None:  # noqa: F811
    out, checkpoint = forged(checkpointed, tmp_path, lambda payload: payload.update(surprise=torch.zeros(3)))
    assert_refused(out, checkpoint, "it holds a key 'surprise'", capsys)


def test_a_zip_directory_is_read_as_zipfile_reads_it(agent_pt, saved) -> None:
    """The member count is bounded on the same directory :mod:`zipfile` reads (a zip with a comment too)."""
    commented = io.BytesIO()
    with zipfile.ZipFile(commented, "w") as archive:
        archive.writestr("a", b"x")
        archive.comment = b"a comment"
    for data in (agent_pt, saved, commented.getvalue()):
        assert [m.filename for m in zip_members(io.BytesIO(data), len(data), 64)] == zipfile.ZipFile(io.BytesIO(data)).namelist()
    with pytest.raises(ValueError, match="at most 2 members"):
        zip_members(io.BytesIO(agent_pt), len(agent_pt), 2)
