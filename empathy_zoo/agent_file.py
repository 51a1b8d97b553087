"""The agent file: a run's trained agent kept beside its result file, and reading it back.

A finished run's acting networks are written atomically as ``runs/<run id>.agent.pt``
(:func:`agent_path` of its result file) by :func:`write_agent_file`, which returns the file's name
and SHA-256 for the result file to record. :func:`load_agent` reads one back as a
:class:`~empathy_zoo.trained_agent.TrainedAgent`, refusing a file whose hash is not the recorded
one, or that is not an agent file; :func:`load_run_agent` loads the one a result file names
(:data:`RESULT_FIELD`). The format (docs/formats.md, "The agent file"):

A ``torch.save`` of one dict, readable with ``torch.load(..., weights_only=True)``:

* ``format``: ``"empathy_zoo.agent"``; ``version``: ``1``;
* ``header``: what the trainer says of the run, as plain data: ``method``, ``settings``, ``env``,
  ``env_kwargs`` (:data:`HEADER_KEYS`), and more (``run_id``, ``seed``, ...);
* ``obs_size``, ``num_actions``: ``V`` and ``A``; ``activation``: ``"relu"`` (between layers);
* ``heads``: ``{name: [W₁, b₁, …, Wₙ, bₙ]}``, float32 tensors, ``W: (in, out)`` applied as
  ``x·W + b``, ``b: (out,)``;
* ``acting``: the head whose largest value is the greedy action.

No replay memory, no optimiser. A learner offers its networks through the optional
``agent_state(run)`` of :class:`agents.base.Learner` (that dict's ``heads`` and ``acting``). A learner
that keeps its agent in a library's own format (Stable-Baselines3) offers ``save_agent(run, file)``
instead; its file is ``runs/<run id>.agent.zip``, the library's zip with one more member,
``empathy_zoo_agent.json`` (the same keys but ``heads`` as names, plus ``library``, ``algorithm`` and
``policy``), and is read back with the library's own ``load`` (:class:`~empathy_zoo.trained_agent.SB3Agent`).
"""

from __future__ import annotations

import hashlib
import io
import json
import math
import re
import zipfile
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
import torch

from empathy_zoo.atomic import read_json, write_bytes_atomic
from empathy_zoo.bounded_read import check_json_depth, read_data
from empathy_zoo.extras import install_command
from empathy_zoo.policies import plain_data_problem
from empathy_zoo.result_file import AGENT_SUFFIXES
from empathy_zoo.trained_agent import SB3Agent, TrainedAgent

__all__ = [
    "FORMAT",
    "VERSION",
    "AGENT_SUFFIX",
    "LIBRARY_AGENT_SUFFIX",
    "LIBRARY_MEMBER",
    "HEADER_KEYS",
    "agent_path",
    "agent_document",
    "agent_bytes",
    "write_agent_bytes",
    "write_agent_file",
    "load_agent",
    "load_run_agent",
    "result_entry",
    "RESULT_FIELD",
    "file_sha256",
]

FORMAT = "empathy_zoo.agent"
"""The ``format`` key of every agent file."""
VERSION = 1
"""The version of the format this module writes (and the newest it reads)."""
AGENT_SUFFIX, LIBRARY_AGENT_SUFFIX = AGENT_SUFFIXES
"""File name endings of an agent file (the result file's ``<run id>.json`` becomes ``<run id>.agent.pt``)
and of an agent kept in a library's own format (Stable-Baselines3's zip, ``<run id>.agent.zip``)."""
LIBRARY_MEMBER = "empathy_zoo_agent.json"
"""The member of a library's zip that holds what :func:`load_agent` needs to read it."""
RESULT_FIELD = "agent"
"""The result file's field naming its agent file: ``{"file": name, "sha256": hex}``, or ``null``."""
HEADER_KEYS = ("method", "settings", "env", "env_kwargs")
"""Keys every header must have (it may hold more: ``run_id``, ``seed``, ``steps``, ``fixed``, ...)."""

MEMBER_BYTES = 64 << 20
"""Largest JSON member of a library's zip read (64 MiB; the suite's are a few KB)."""

_HEAD_NAME = re.compile(r"^[a-z_][a-z0-9_]*$")
_LIBRARIES = {"stable_baselines3": ("DQN", "PPO")}
"""Libraries (and their classes) whose own agent files :func:`load_agent` reads."""


def agent_path(result_file: str | Path) -> Path:
    """Where the agent of the run whose result file is ``result_file`` (``runs/<run id>.json``) goes:
    ``runs/<run id>.agent.pt``."""
    result_file = Path(result_file)
    if result_file.suffix != ".json":
        raise ValueError(f"{result_file} is not a result file (<run id>.json)")
    return result_file.with_name(result_file.stem + AGENT_SUFFIX)


def file_sha256(path: str | Path) -> str:
    """The SHA-256 (hex) of the agent file at ``path`` (read through the bounded reader)."""
    return hashlib.sha256(read_data(path, "agent file")).hexdigest()


# ---------------------------------------------------------------------------- building and checking
def _check_header(header: Any) -> dict[str, Any]:
    if not isinstance(header, Mapping):
        raise ValueError(f"an agent file's header is a dict, got {type(header).__name__}")
    missing = [key for key in HEADER_KEYS if key not in header]
    if missing:
        raise ValueError(f"an agent file's header needs {', '.join(HEADER_KEYS)}; missing {', '.join(missing)}")
    problem = plain_data_problem(header, arrays=False, where="the header")
    if problem:
        raise ValueError(f"an agent file's header must be plain data: {problem}")
    return json.loads(json.dumps(dict(header)))  # (tuples become lists, as when it is read back)


def _as_tensor(value: Any, where: str) -> torch.Tensor:
    if isinstance(value, np.ndarray):
        value = torch.from_numpy(value)
    if not isinstance(value, torch.Tensor):
        raise ValueError(f"{where} is a {type(value).__name__}, not a tensor or numpy array")
    if value.layout != torch.strided or value.is_quantized:
        raise ValueError(f"{where} is a {value.layout} tensor, not a dense one")
    if value.dtype != torch.float32:
        raise ValueError(f"{where} is {value.dtype}, not float32 (convert it: an agent computes in float32)")
    return value.detach().to("cpu").clone().contiguous()  # (a copy of its own storage, not the ensemble's)


def _check_heads(heads: Any, acting: Any) -> tuple[dict[str, list[torch.Tensor]], int, int]:
    """``heads`` as ``{name: [W (in, out), b (out,), ...]}`` float32 CPU copies, and ``(V, A)``;
    anything else raises ``ValueError`` naming the head and the layer."""
    if not isinstance(heads, Mapping) or not heads:
        raise ValueError("'heads' must be a non-empty dict {name: [W1, b1, W2, b2, ...]}")
    checked: dict[str, list[torch.Tensor]] = {}
    sizes: set[tuple[int, int]] = set()
    for name, layers in heads.items():
        if not isinstance(name, str) or not _HEAD_NAME.match(name):
            raise ValueError(f"head name {name!r} must be a lower-case identifier (like 'q' or 'q_emp')")
        if not isinstance(layers, (list, tuple)) or not layers or len(layers) % 2:
            raise ValueError(f"head {name!r} must be a list [W1, b1, W2, b2, ...] of weights and biases")
        tensors: list[torch.Tensor] = []
        width = None
        for layer in range(len(layers) // 2):
            weight = _as_tensor(layers[2 * layer], f"head {name!r} weight {layer + 1}")
            bias = _as_tensor(layers[2 * layer + 1], f"head {name!r} bias {layer + 1}")
            if weight.dim() != 2:
                raise ValueError(f"head {name!r} weight {layer + 1} must be (in, out), got shape {tuple(weight.shape)}")
            if width is not None and weight.shape[0] != width:
                raise ValueError(
                    f"head {name!r} weight {layer + 1} takes {weight.shape[0]} inputs; the layer before gives {width}"
                )
            width = int(weight.shape[1])
            if bias.shape not in ((width,), (1, width)):
                raise ValueError(f"head {name!r} bias {layer + 1} must be ({width},), got shape {tuple(bias.shape)}")
            tensors += [weight, bias.reshape(width)]
        checked[name] = tensors
        sizes.add((int(tensors[0].shape[0]), int(tensors[-1].shape[0])))
    if len(sizes) != 1:
        raise ValueError(f"every head must take the same observation and give the same actions; got (in, out) {sorted(sizes)}")
    if acting not in checked:
        raise ValueError(f"'acting' must name one of the heads {sorted(checked)}, got {acting!r}")
    ((obs_size, num_actions),) = sizes
    return checked, obs_size, num_actions


def agent_document(state: Mapping[str, Any], header: Mapping[str, Any]) -> dict[str, Any]:
    """The dict an agent file holds, from a learner's ``agent_state(run)`` (``heads``, ``acting``)
    and the trainer's ``header``; bad input raises ``ValueError`` saying what is wrong."""
    if not isinstance(state, Mapping) or set(state) != {"heads", "acting"}:
        keys = sorted(state) if isinstance(state, Mapping) else type(state).__name__
        raise ValueError(f"agent_state(run) must return {{'heads': ..., 'acting': ...}}, got {keys}")
    heads, obs_size, num_actions = _check_heads(state["heads"], state["acting"])
    return {
        "format": FORMAT,
        "version": VERSION,
        "header": _check_header(header),
        "obs_size": obs_size,
        "num_actions": num_actions,
        "activation": "relu",
        "heads": heads,
        "acting": state["acting"],
    }


# ---------------------------------------------------------------------------- writing
def agent_bytes(learner: Any, run: int, header: Mapping[str, Any]) -> tuple[str, bytes] | None:
    """Run ``run``'s trained agent of ``learner`` as the bytes of its agent file and that file's
    suffix (:data:`AGENT_SUFFIX`, or :data:`LIBRARY_AGENT_SUFFIX` for a library's own format);
    ``None`` when the learner keeps no agent (it has neither ``agent_state`` nor ``save_agent``).
    ``header`` is plain data with at least :data:`HEADER_KEYS` (the trainer passes the run's id and
    configuration)."""
    if callable(getattr(learner, "agent_state", None)):
        buffer = io.BytesIO()
        torch.save(agent_document(learner.agent_state(run), header), buffer)
        return AGENT_SUFFIX, buffer.getvalue()
    if callable(getattr(learner, "save_agent", None)):
        return LIBRARY_AGENT_SUFFIX, _library_file(learner, run, header)
    return None


def write_agent_bytes(path: str | Path, suffix: str, data: bytes) -> tuple[str, str]:
    """Write an agent file's ``data`` atomically at ``path`` (``runs/<run id>.agent.pt``,
    :func:`agent_path`), with ``suffix`` in place of :data:`AGENT_SUFFIX`; return ``(file name,
    SHA-256)``, what the result file records."""
    path = Path(path)
    if not path.name.endswith(AGENT_SUFFIX):
        raise ValueError(f"an agent file's name ends in {AGENT_SUFFIX}, got {path}")
    path = path.with_name(path.name.removesuffix(AGENT_SUFFIX) + suffix)
    write_bytes_atomic(path, data)
    return path.name, hashlib.sha256(data).hexdigest()


def write_agent_file(learner: Any, run: int, path: str | Path, header: Mapping[str, Any]) -> tuple[str, str] | None:
    """Write run ``run``'s trained agent of ``learner`` atomically at ``path`` (:func:`agent_bytes`,
    :func:`write_agent_bytes`) and return ``(file name, SHA-256)``; ``None`` when the learner keeps
    no agent."""
    made = agent_bytes(learner, run, header)
    return None if made is None else write_agent_bytes(path, *made)


def result_entry(written: tuple[str, str] | None) -> dict[str, str] | None:
    """What the result file records in :data:`RESULT_FIELD` for what :func:`write_agent_file` returned."""
    return None if written is None else {"file": written[0], "sha256": written[1]}


def _library_file(learner: Any, run: int, header: Mapping[str, Any]) -> bytes:
    """The library's own zip of run ``run`` with :data:`LIBRARY_MEMBER` added."""
    buffer = io.BytesIO()
    info = learner.save_agent(run, buffer)
    if not isinstance(info, Mapping) or info.get("library") not in _LIBRARIES:
        raise ValueError(f"save_agent(run, file) must return {{'library': one of {sorted(_LIBRARIES)}, ...}}, got {info!r}")
    if info.get("algorithm") not in _LIBRARIES[info["library"]]:
        raise ValueError(
            f"save_agent: {info['library']} algorithm must be one of {_LIBRARIES[info['library']]}, got {info.get('algorithm')!r}"
        )
    member = {
        "format": FORMAT,
        "version": VERSION,
        "header": _check_header(header),
        "library": info["library"],
        "algorithm": info["algorithm"],
        "policy": str(info.get("policy", "MlpPolicy")),
        "obs_size": int(info["obs_size"]),
        "num_actions": int(info["num_actions"]),
        "heads": [str(h) for h in info.get("heads", [])],
        "acting": str(info["acting"]),
    }
    with zipfile.ZipFile(buffer, "a") as archive:
        if LIBRARY_MEMBER in archive.namelist():
            raise ValueError(f"save_agent wrote a member {LIBRARY_MEMBER!r} of its own; that name is the suite's")
        archive.writestr(LIBRARY_MEMBER, json.dumps(member, sort_keys=True))
    return buffer.getvalue()


# ---------------------------------------------------------------------------- reading
def load_agent(
    path: str | Path, expected_sha256: str | None = None, *, result_file: str | Path | None = None
) -> TrainedAgent | SB3Agent:
    """The trained agent of the agent file at ``path`` (a ``TrainedAgent``; an ``SB3Agent`` for a
    Stable-Baselines3 ``.agent.zip``), read with ``torch.load(..., weights_only=True)``.

    With ``expected_sha256`` (what the result file records) a file whose SHA-256 differs raises
    ``ValueError`` naming the agent file and, when given, ``result_file``; so does a file that is not
    an agent file, or one of a newer format version."""
    path = Path(path)
    data = read_data(path, "agent file")
    sha256 = hashlib.sha256(data).hexdigest()
    if expected_sha256 is not None and sha256 != str(expected_sha256).lower():
        recorded = f"its result file {result_file} records" if result_file is not None else "expected"
        raise ValueError(
            f"agent file {path} has SHA-256 {sha256}, but {recorded} {expected_sha256}: "
            "it was changed or replaced after the run wrote it; refusing to load it"
        )
    source = {"file": str(path), "sha256": sha256}
    if zipfile.is_zipfile(io.BytesIO(data)):
        with zipfile.ZipFile(io.BytesIO(data)) as archive:
            if LIBRARY_MEMBER in archive.namelist():
                return _load_library_agent(path, data, _read_member(path, archive), source)
    try:
        document = torch.load(io.BytesIO(data), map_location="cpu", weights_only=True)
    except Exception as error:  # (torch raises several kinds for a file that is no torch.save)
        raise ValueError(f"{path} is not an empathy-zoo agent file (torch.load with weights_only=True fails: {error})") from None
    _check_format(path, document)
    try:
        heads, obs_size, num_actions = _check_heads(document.get("heads"), document.get("acting"))
        for name, layers in heads.items():
            if not all(bool(torch.isfinite(layer).all()) for layer in layers):
                raise ValueError(f"head {name!r} holds a weight that is no finite number")
        header = _check_header(document.get("header"))
        if (document.get("obs_size"), document.get("num_actions")) != (obs_size, num_actions):
            raise ValueError(
                f"its sizes {document.get('obs_size')}→{document.get('num_actions')} "
                f"are not its networks' {obs_size}→{num_actions}"
            )
        if document.get("activation") != "relu":
            raise ValueError(f"activation {document.get('activation')!r} (this version knows 'relu')")
    except ValueError as error:
        raise ValueError(f"agent file {path} is malformed: {error}") from None
    description = _description(header, obs_size, num_actions, list(heads), document["acting"], source)
    description["layers"] = [obs_size] + [int(t.shape[0]) for t in heads[document["acting"]][1::2]]
    return TrainedAgent(heads, document["acting"], description)


def load_run_agent(result_file: str | Path) -> TrainedAgent | SB3Agent:
    """The trained agent of the run whose result file is ``result_file``: the agent file it names
    in :data:`RESULT_FIELD`, beside it, checked against the SHA-256 it records (:func:`load_agent`);
    a run that kept no agent raises ``ValueError`` naming the result file."""
    result_file = Path(result_file)
    document = read_json(result_file)
    entry = document.get(RESULT_FIELD) if isinstance(document, dict) else None
    if entry is None:
        raise ValueError(f"result file {result_file} names no agent file: its run kept no trained agent")
    if not isinstance(entry, Mapping) or not isinstance(entry.get("file"), str) or not isinstance(entry.get("sha256"), str):
        raise ValueError(f"result file {result_file}: {RESULT_FIELD!r} must be {{'file': name, 'sha256': hex}}, got {entry!r}")
    name = Path(entry["file"])
    if name.name != entry["file"]:
        raise ValueError(f"result file {result_file}: its agent file {entry['file']!r} must be a file name beside it")
    return load_agent(result_file.parent / name, entry["sha256"], result_file=result_file)


def _check_format(path: Path, document: Any) -> None:
    if not isinstance(document, Mapping) or document.get("format") != FORMAT:
        found = document.get("format") if isinstance(document, Mapping) else type(document).__name__
        raise ValueError(f"{path} is not an empathy-zoo agent file (format {found!r}, expected {FORMAT!r})")
    version = document.get("version")
    if not isinstance(version, int) or isinstance(version, bool) or not 1 <= version <= VERSION:
        raise ValueError(f"agent file {path} has format version {version!r}; this empathy-zoo reads versions 1 to {VERSION}")


def _description(
    header: Mapping[str, Any], obs_size: int, num_actions: int, heads: list[str], acting: str, source: Mapping[str, str]
) -> dict[str, Any]:
    return {**header, "obs_size": obs_size, "num_actions": num_actions, "heads": heads, "acting": acting, **source}


def _json_member(path: Path, archive: zipfile.ZipFile, name: str) -> Any:
    """The JSON member ``name`` of a library's zip, at most :data:`MEMBER_BYTES` and nested no
    deeper than the bounded reader allows (``ValueError`` naming the agent file otherwise)."""
    if archive.getinfo(name).file_size > MEMBER_BYTES:
        raise ValueError(f"agent file {path}: its member {name} is larger than {MEMBER_BYTES:,} bytes")
    data = archive.read(name)
    check_json_depth(data, f"agent file {path}: its member {name}")
    try:
        return json.loads(data)
    except (ValueError, RecursionError) as error:
        raise ValueError(f"agent file {path}: its {name} is corrupted ({error})") from None


def _read_member(path: Path, archive: zipfile.ZipFile) -> dict[str, Any]:
    member = _json_member(path, archive, LIBRARY_MEMBER)
    _check_format(path, member)
    if member.get("library") not in _LIBRARIES or member.get("algorithm") not in _LIBRARIES.get(member.get("library"), ()):
        raise ValueError(
            f"agent file {path} holds a {member.get('library')!r} {member.get('algorithm')!r} model, "
            "which this empathy-zoo does not read"
        )
    return member


def _load_library_agent(path: Path, data: bytes, member: Mapping[str, Any], source: Mapping[str, str]) -> SB3Agent:
    """A Stable-Baselines3 agent file read with SB3's own ``load``, every pickled entry of its
    ``data`` replaced by an object built here (so nothing is unpickled: SB3 reads the networks with
    ``weights_only=True``)."""
    try:
        import stable_baselines3 as sb3
    except ImportError:
        raise ImportError(f"{path} is a Stable-Baselines3 agent: install it with {install_command('sb3')}") from None
    cls = getattr(sb3, member["algorithm"])
    with zipfile.ZipFile(io.BytesIO(data)) as archive:
        saved = _json_member(path, archive, "data")
    custom = _sb3_custom_objects(cls, member, saved)
    pickled = sorted(key for key, value in saved.items() if isinstance(value, dict) and ":serialized:" in value)
    unknown = [key for key in pickled if key not in custom]
    if unknown:
        raise ValueError(
            f"agent file {path} holds pickled objects {unknown} this loader does not rebuild; refusing to unpickle them"
        )
    model = cls.load(io.BytesIO(data), device="cpu", custom_objects=custom)
    header = _check_header(member["header"])
    description = _description(
        header, int(member["obs_size"]), int(member["num_actions"]), list(member["heads"]), member["acting"], source
    )
    description.update(library=member["library"], algorithm=member["algorithm"])
    return SB3Agent(model, member["heads"], member["acting"], description)


def _sb3_custom_objects(cls: Any, member: Mapping[str, Any], saved: Mapping[str, Any]) -> dict[str, Any]:
    """What replaces the pickled entries of an SB3 ``data`` file: the spaces the suite's SB3 learner
    builds (``Box(-inf, inf, (V,), float32)``, ``Discrete(A)``), the policy class by its alias, SB3's
    buffer classes, constant schedules and no last observations or episode buffers (they serve only
    training); DQN's replay memory is made one transition long (a loaded agent only acts)."""
    import gymnasium
    from stable_baselines3.common.buffers import ReplayBuffer, RolloutBuffer
    from stable_baselines3.common.type_aliases import TrainFreq, TrainFrequencyUnit

    def constant(value: float) -> Any:
        return lambda _progress: value

    custom: dict[str, Any] = {
        "observation_space": gymnasium.spaces.Box(-math.inf, math.inf, (int(member["obs_size"]),), np.float32),
        "action_space": gymnasium.spaces.Discrete(int(member["num_actions"])),
        "policy_class": cls.policy_aliases[member["policy"]],
        "replay_buffer_class": ReplayBuffer,
        "rollout_buffer_class": RolloutBuffer,
        "train_freq": TrainFreq(1, TrainFrequencyUnit.STEP),
        "lr_schedule": constant(0.0),
        "exploration_schedule": constant(0.0),
        "clip_range": constant(0.2),
        "clip_range_vf": None,
        **dict.fromkeys(("_last_obs", "_last_original_obs", "_last_episode_starts", "ep_info_buffer", "ep_success_buffer")),
    }
    if "buffer_size" in saved:
        custom["buffer_size"] = 1
    return {key: value for key, value in custom.items() if key in saved}
