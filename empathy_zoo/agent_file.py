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

Before anything of a file is decompressed or loaded, its zip directory is read
(:func:`~empathy_zoo.safe_data.zip_members`): an agent file is a zip of at most
:data:`MAX_MEMBERS` members of the records ``torch.save`` writes, stored as they are
(:func:`~empathy_zoo.safe_data.torch_zip_problem`), or a library's zip of its members
(:data:`LIBRARY_MEMBERS`, stored or deflated, together at most the agent file's size cap once
expanded; each ``.pth`` of them a zip of ``torch.save`` in turn). A key an agent file does not have
(:data:`DOCUMENT_KEYS`, :data:`LIBRARY_MEMBER_KEYS`, and SB3's ``data``: :mod:`empathy_zoo.sb3_agent_data`)
is refused, naming the file and the key.
"""

from __future__ import annotations

import hashlib
import io
import json
import math
import re
import zipfile
import zlib
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
import torch

from empathy_zoo import run_ids
from empathy_zoo.atomic import read_json, write_bytes_atomic
from empathy_zoo.bounded_read import CAPS, check_json_depth, parse_json, read_data
from empathy_zoo.document_checks import DocumentChecker, one_line, shown
from empathy_zoo.environments import ENGINES
from empathy_zoo.extras import install_command
from empathy_zoo.import_names import MAX_PLUGIN_NAME, PLUGIN_NAME
from empathy_zoo.limits import MAX_EVAL_EPISODES, MAX_HIDDEN_SIZE, MAX_SEED, MAX_SIZE, MAX_STEPS
from empathy_zoo.policies import plain_data_problem
from empathy_zoo.result_file import AGENT_SUFFIXES, check_env_kwargs
from empathy_zoo.safe_data import torch_zip_problem, zip_members
from empathy_zoo.sb3_agent_data import ACTING_ONLY, check_sb3_data
from empathy_zoo.trained_agent import SB3Agent, TrainedAgent

__all__ = [
    "AgentFileError",
    "FORMAT",
    "VERSION",
    "AGENT_SUFFIX",
    "LIBRARY_AGENT_SUFFIX",
    "LIBRARY_MEMBER",
    "LIBRARY_MEMBERS",
    "LIBRARY_MEMBER_KEYS",
    "DOCUMENT_KEYS",
    "MAX_MEMBERS",
    "HEADER_KEYS",
    "agent_path",
    "agent_document",
    "agent_bytes",
    "write_agent_bytes",
    "write_agent_file",
    "load_agent",
    "load_run_agent",
    "check_against_result",
    "check_agent_hash",
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
HEADER_OPTIONAL = (
    "run_id",
    "variant",
    "fixed",
    "reward",
    "description",
    "seed",
    "steps",
    "eval_interval",
    "eval_episodes",
    "label",
)
"""The other keys a header read back may have: the trainer writes the run's id and configuration
(``{"run_id": ..., **RunSpec.config()}``), as its result file records them; no others."""
METHOD_NAME = re.compile(r"[a-z][a-z0-9_]*")
"""What the name of a registered method looks like (``empathic_dqn``); any other ``method`` of a
header is a ``package.module:NAME`` plug-in (:data:`~empathy_zoo.import_names.PLUGIN_NAME`), kept as
text and never imported."""

DOCUMENT_KEYS = ("format", "version", "header", "obs_size", "num_actions", "activation", "heads", "acting")
"""The keys of an agent file's dict (no other is read)."""
LIBRARY_MEMBER_KEYS = (
    "format",
    "version",
    "header",
    "library",
    "algorithm",
    "policy",
    "obs_size",
    "num_actions",
    "heads",
    "acting",
)
"""The keys of :data:`LIBRARY_MEMBER`."""
LIBRARY_MEMBERS = (
    LIBRARY_MEMBER,
    "data",
    "policy.pth",
    "policy.optimizer.pth",
    "pytorch_variables.pth",
    "_stable_baselines3_version",
    "system_info.txt",
)
"""The members of a Stable-Baselines3 agent file: what SB3's ``save`` writes of a DQN or a PPO, and
:data:`LIBRARY_MEMBER`; each ``.pth`` is a ``torch.save`` zip (``pytorch_variables.pth`` of ``{}``:
DQN and PPO keep no variables besides their networks)."""
MAX_MEMBERS = 4096
"""Most members of an agent file's zip (and of each ``.pth`` zip in a library's): a ``torch.save``
archive holds a few records and one per tensor, two per layer of each head."""
MEMBER_BYTES = 64 << 20
"""Largest JSON member of a library's zip read (64 MiB; the suite's are a few KB)."""
MAX_OBSERVATION = (MAX_SIZE - 1) ** 2
"""Most values of an observation an agent file may say its agent takes (``obs_size``, ``view²``
with ``view < size <= MAX_SIZE``); ``num_actions`` is bounded by it too."""
MESSAGE_CHARS = 300
"""Most characters of a library's error (torch's, a zip's) quoted in a refusal, in one line."""
_ZIP_ERRORS = (zipfile.BadZipFile, zipfile.LargeZipFile, zlib.error, EOFError, NotImplementedError, RuntimeError, OSError)
"""What reading a damaged zip raises (a bad CRC, a truncated member, an unknown compression, an
encrypted member)."""


class AgentFileError(ValueError):
    """An agent file is not what this suite writes; the message names the file (and the field)."""


def _why(error: BaseException) -> str:
    """A library's ``error`` (torch's, a zip's) as a refusal quotes it: its kind and message in one
    line (torch's weights-only message spans several), cut at :data:`MESSAGE_CHARS`."""
    return one_line(f"{type(error).__name__}: {error}", MESSAGE_CHARS)


_HEAD_NAME = re.compile(r"[a-z][a-z0-9_]*")
"""A head's name: a lower-case identifier that starts with a letter (never ``__class__``), the
whole name (matched with ``fullmatch``: ``$`` would let a trailing line break through)."""
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


def _written_header(
    header: Any, obs_size: int, num_actions: int, heads: Mapping[str, list[torch.Tensor]] | None = None
) -> dict[str, Any]:
    """``header`` as a writer stores it (:func:`_check_header`), once every field is one the readers
    take, beside networks of ``obs_size`` inputs, ``num_actions`` outputs and (where given) the
    layers of ``heads`` (:func:`_check_header_fields`, :func:`_check_header_run_id`,
    :func:`_check_hidden_size`, :func:`_check_env_sizes`): no agent file is written that they
    refuse; ``ValueError`` naming the field otherwise."""
    checked = _check_header(header)
    check = DocumentChecker(
        Path("the agent file's header to write"),
        ValueError,
        "an agent file's header",
        "a header the readers take",
        "write the run's configuration as the trainer does (docs/formats.md, the agent file)",
    )
    _check_header_fields(Path(), checked, check)
    _check_header_run_id(Path(), checked, check)
    if heads is not None:
        _check_hidden_size(Path(), checked, heads, check)
    _check_env_sizes(Path(), checked, obs_size, num_actions, check)
    return checked


def _header_run_id(header: Mapping[str, Any], seed: int) -> str:
    """The run id ``header``'s own fields give (:func:`~empathy_zoo.run_ids.run_id`: the trainer
    writes ``{"run_id": ..., **config}``)."""
    config = {key: value for key, value in header.items() if key != "run_id"}
    return run_ids.run_id(str(header.get("variant") or header["env"]), header["method"], config, seed)


def _as_tensor(value: Any, where: str, budget: list[int] | None = None) -> torch.Tensor:
    """``value`` (a float32 dense tensor or numpy array) as a CPU copy of its own. With ``budget``
    (``[bytes left]``), its elements are counted first and the copy refused when it would take
    more bytes than are left (they are then taken): a tensor expanded from one stored value (stride
    0) is tiny in a file and huge once copied."""
    if isinstance(value, np.ndarray):
        value = torch.from_numpy(value)
    if not isinstance(value, torch.Tensor):
        raise ValueError(f"{where} is a {type(value).__name__}, not a tensor or numpy array")
    if value.layout != torch.strided or value.is_quantized:
        raise ValueError(f"{where} is a {value.layout} tensor, not a dense one")
    if value.dtype != torch.float32:
        raise ValueError(f"{where} is {value.dtype}, not float32 (convert it: an agent computes in float32)")
    if budget is not None:
        size = math.prod(int(n) for n in value.shape) * value.element_size()  # (Python ints: no overflow)
        if size > budget[0]:
            raise ValueError(
                f"{where} of shape {tuple(value.shape)} takes {size:,} bytes, more than the file's weights can hold "
                f"({budget[0]:,} bytes left of its size: an agent file stores every weight it has)"
            )
        budget[0] -= size
    return value.detach().to("cpu").clone().contiguous()  # (a copy of its own storage, not the ensemble's)


def _check_heads(heads: Any, acting: Any, budget: int | None = None) -> tuple[dict[str, list[torch.Tensor]], int, int]:
    """``heads`` as ``{name: [W (in, out), b (out,), ...]}`` float32 CPU copies, and ``(V, A)``;
    anything else raises ``ValueError`` naming the head and the layer. With ``budget`` (the bytes of
    the file they were read from), their elements together may take no more bytes than that, each
    counted before it is copied."""
    if not isinstance(heads, Mapping) or not heads:
        raise ValueError("'heads' must be a non-empty dict {name: [W1, b1, W2, b2, ...]}")
    left = None if budget is None else [budget]
    checked: dict[str, list[torch.Tensor]] = {}
    sizes: set[tuple[int, int]] = set()
    for name, layers in heads.items():
        if not isinstance(name, str) or not _HEAD_NAME.fullmatch(name):
            raise ValueError(f"head name {name!r} must be a lower-case identifier (like 'q' or 'q_emp')")
        if not isinstance(layers, (list, tuple)) or not layers or len(layers) % 2:
            raise ValueError(f"head {name!r} must be a list [W1, b1, W2, b2, ...] of weights and biases")
        tensors: list[torch.Tensor] = []
        width = None
        for layer in range(len(layers) // 2):
            weight = _as_tensor(layers[2 * layer], f"head {name!r} weight {layer + 1}", left)
            bias = _as_tensor(layers[2 * layer + 1], f"head {name!r} bias {layer + 1}", left)
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
        if not all(bool(torch.isfinite(layer).all()) for layer in tensors):
            raise ValueError(f"head {name!r} holds a weight that is no finite number")  # (read or about to be written)
        checked[name] = tensors
        sizes.add((int(tensors[0].shape[0]), int(tensors[-1].shape[0])))
    if len(sizes) != 1:
        raise ValueError(f"every head must take the same observation and give the same actions; got (in, out) {sorted(sizes)}")
    if not isinstance(acting, str) or acting not in checked:  # (a list or dict is no name: never hashed)
        raise ValueError(f"'acting' must name one of the heads {sorted(checked)}, got {shown(acting)}")
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
        "header": _written_header(header, obs_size, num_actions, heads),
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
        "header": _written_header(header, int(info["obs_size"]), int(info["num_actions"])),
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
    path: str | Path,
    expected_sha256: str | None = None,
    *,
    result_file: str | Path | None = None,
    recorded: Mapping[str, Any] | None = None,
) -> TrainedAgent | SB3Agent:
    """The trained agent of the agent file at ``path`` (a ``TrainedAgent``; an ``SB3Agent`` for a
    Stable-Baselines3 ``.agent.zip``), read with ``torch.load(..., weights_only=True)``.

    With ``expected_sha256`` (what the result file records) a file whose SHA-256 differs raises
    ``ValueError`` naming the agent file and, when given, ``result_file``; so does a file that is not
    an agent file, or one of a newer format version. With ``result_file`` (whose document is
    ``recorded``, else read here), the header must be the run that file records
    (:func:`check_against_result`)."""
    path = Path(path)
    data = read_data(path, "agent file")
    sha256 = hashlib.sha256(data).hexdigest()
    if expected_sha256 is not None:
        _check_sha256(path, sha256, expected_sha256, result_file)
    source = {"file": str(path), "sha256": sha256}
    members = _zip_members(path, data)
    member = _library_member(path, data, members)
    if member is not None:
        if result_file is not None:
            check_against_result(path, member["header"], result_file, recorded)
        _check_header_run_id(path, member["header"])
        _check_env_sizes(path, member["header"], int(member["obs_size"]), int(member["num_actions"]))
        return _load_library_agent(path, data, member, source)
    problem = torch_zip_problem(members, len(data))
    if problem:
        raise AgentFileError(f"{path} is not an empathy-zoo agent file ({problem})")
    try:
        document = torch.load(io.BytesIO(data), map_location="cpu", weights_only=True)
    except Exception as error:  # (torch raises several kinds for a file that is no torch.save)
        raise AgentFileError(
            f"{path} is not an empathy-zoo agent file (torch.load with weights_only=True fails: {_why(error)})"
        ) from None
    _check_format(path, document)
    _check_keys(path, document, DOCUMENT_KEYS, "agent file")
    try:
        heads, obs_size, num_actions = _check_heads(document.get("heads"), document.get("acting"), budget=len(data))
        header = _check_header(document.get("header"))
        sizes = (document.get("obs_size"), document.get("num_actions"))
        if not all(type(size) is int for size in sizes) or sizes != (obs_size, num_actions):  # (no tensor, float or bool)
            raise ValueError(
                f"its sizes {shown(document.get('obs_size'))}→{shown(document.get('num_actions'))} "
                f"are not its networks' {obs_size}→{num_actions}"
            )
        if document.get("activation") != "relu":
            raise ValueError(f"activation {shown(document.get('activation'))} (this version knows 'relu')")
    except RecursionError:
        raise AgentFileError(f"agent file {path} is malformed: its data is nested too deep") from None
    except ValueError as error:
        raise AgentFileError(f"agent file {path} is malformed: {one_line(str(error), MESSAGE_CHARS)}") from None
    header = _check_header_fields(path, header)
    _check_hidden_size(path, header, heads)
    if result_file is not None:
        check_against_result(path, header, result_file, recorded)
    _check_header_run_id(path, header)
    _check_env_sizes(path, header, obs_size, num_actions)
    description = _description(header, obs_size, num_actions, list(heads), document["acting"], source)
    description["layers"] = [obs_size] + [int(t.shape[0]) for t in heads[document["acting"]][1::2]]
    return TrainedAgent(heads, document["acting"], description)


def check_agent_hash(path: str | Path, expected_sha256: str, result_file: str | Path | None = None) -> None:
    """Refuse the agent file at ``path`` as :func:`load_agent` refuses it when its SHA-256 is not
    ``expected_sha256`` (what ``result_file`` records): the same ``ValueError``, naming both files.
    Nothing of it is loaded: the file is read through the bounded reader (a file over the agent
    file's cap, or one that is no regular file, raises as there) and hashed, no more; a check
    before work that ends in :func:`load_agent` (``empathy-zoo reproduce`` before it trains)."""
    path = Path(path)
    _check_sha256(path, file_sha256(path), expected_sha256, result_file)


def _check_sha256(path: Path, sha256: str, expected_sha256: str, result_file: str | Path | None) -> None:
    if sha256 != str(expected_sha256).lower():
        records = f"its result file {result_file} records" if result_file is not None else "expected"
        raise ValueError(
            f"agent file {path} has SHA-256 {sha256}, but {records} {expected_sha256}: "
            "it was changed or replaced after the run wrote it; refusing to load it"
        )


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
    return load_agent(result_file.parent / name, entry["sha256"], result_file=result_file, recorded=document)


def check_against_result(
    path: str | Path, header: Mapping[str, Any], result_file: str | Path, recorded: Mapping[str, Any] | None = None
) -> None:
    """Refuse (:class:`AgentFileError` naming the agent file ``path``, the field and ``result_file``)
    a header (checked) that is not the run its result file records: the trainer writes both from one
    run (``{"run_id": ..., **config}``), so every field of the header the result file's ``config``
    holds too (the environment and its arguments, partners, method, settings, reward, seed, budget,
    label) is equal to it, and ``run_id`` to its ``run_id``. A field the result file records that the
    header leaves out is refused too: ``watch`` builds its world from the header, so a header that
    drops its partners would play beside others than the run's. ``recorded``: the result file's
    document, else it is read (bounded)."""
    document = read_json(result_file, "result file") if recorded is None else recorded
    if not isinstance(document, Mapping):
        raise AgentFileError(f"agent file {path}: its result file {result_file} is no JSON object to check it against")
    config = document.get("config")
    config = config if isinstance(config, Mapping) else {}  # (what a result file holds is checked by its reader)
    pairs = [("run_id", "run_id", document["run_id"])] if "run_id" in document else []
    pairs += [(key, f"config.{key}", config[key]) for key in config if key != "run_id"]
    for key, where, value in pairs:
        if key not in header:
            raise AgentFileError(
                f"agent file {path}: its header has no field {key}, but its result file {result_file} records {where} "
                f"{shown(value)}: the agent file is not that run's as written; move it away (train the run again to make it anew)"
            )
        if header[key] != value:
            raise AgentFileError(
                f"agent file {path}: field header.{key}: {shown(header[key])}, but its result file {result_file} records "
                f"{where} {shown(value)}: the agent file is not that run's; move it away (train the run again to make it anew)"
            )


def _check_header_run_id(path: Path, header: Mapping[str, Any], check: DocumentChecker | None = None) -> None:
    """Refuse (:class:`AgentFileError` naming the file and the field) a header (checked) whose
    ``run_id`` is not the id its own fields give (:func:`~empathy_zoo.run_ids.run_id`: the trainer
    writes ``{"run_id": ..., **config}``), so an agent read alone (``watch``) is the run it names.
    Checked after the comparison with a result file, whose message names both files; a header
    with a ``run_id`` must hold its ``seed`` (a whole number), one without has no id to compare."""
    if "run_id" not in header:
        return
    check = check or _checker(path)
    seed = check.integer(header.get("seed"), "header.seed", 0, MAX_SEED)  # (a run id ends with its seed)
    expected = _header_run_id(header, seed)
    if header["run_id"] != expected:
        raise check.fail(
            "header.run_id",
            f"{expected} (the id its header gives: a hash of the run's configuration without seed and description)",
            header["run_id"],
        )


def _check_env_sizes(
    path: Path, header: Mapping[str, Any], obs_size: int, num_actions: int, check: DocumentChecker | None = None
) -> None:
    """Refuse (:class:`AgentFileError` naming the file and the field) an agent whose networks do
    not fit the environment its header (checked) names: ``num_actions`` outputs, one per action of
    its engine, and an input of the observation its ``env_kwargs`` give (the environment is built
    for one episode to measure it; nothing is played). Checked last, so a header that contradicts
    its result file is named as such first; before anything is played or written."""
    check = check or _checker(path)
    engine = ENGINES[header["env"]]
    if num_actions != engine.num_actions:
        raise check.fail(
            "num_actions", f"{engine.num_actions}, the actions of {header['env']} (its networks' outputs)", num_actions
        )
    try:
        size = int(engine(1, **header["env_kwargs"]).obs_size)
    except ValueError as error:
        raise check.fail(
            "header.env_kwargs", f"arguments {header['env']} is built with ({one_line(str(error), 200)})", header["env_kwargs"]
        ) from None
    if size != obs_size:
        raise check.fail(
            "header.env_kwargs",
            f"arguments giving the observation its network reads ({obs_size:,} values; {header['env']} with these "
            f"gives {size:,})",
            header["env_kwargs"],
        )


def _check_hidden_size(
    path: Path, header: Mapping[str, Any], heads: Mapping[str, list[torch.Tensor]], check: DocumentChecker | None = None
) -> None:
    """Refuse (:class:`AgentFileError` naming the file and the field) a header whose
    ``settings.hidden_size`` is not the width of every hidden layer of every head (a registered
    method's networks are ``obs → hidden → hidden → actions``). A plug-in's settings are its own:
    only their shape is checked, as a result file's."""
    settings = header["settings"]
    if "hidden_size" not in settings or PLUGIN_NAME.fullmatch(header["method"]):
        return
    check = check or _checker(path)
    hidden = check.integer(settings["hidden_size"], "header.settings.hidden_size", 1, MAX_HIDDEN_SIZE)
    widths = sorted({int(layer.shape[0]) for layers in heads.values() for layer in layers[1:-1:2]})
    if widths != [hidden]:
        raise check.fail(
            "header.settings.hidden_size",
            f"the width of every hidden layer of its networks ({', '.join(map(str, widths)) or 'none'})",
            settings["hidden_size"],
        )


def _check_format(path: Path, document: Any) -> None:
    if not isinstance(document, Mapping) or document.get("format") != FORMAT:
        found = shown(document.get("format")) if isinstance(document, Mapping) else repr(type(document).__name__)
        raise AgentFileError(f"{path} is not an empathy-zoo agent file (format {found}, expected {FORMAT!r})")
    version = document.get("version")
    if not isinstance(version, int) or isinstance(version, bool) or not 1 <= version <= VERSION:
        raise AgentFileError(
            f"agent file {path} has format version {shown(version)}; this empathy-zoo reads versions 1 to {VERSION}"
        )


def _check_keys(path: Path, document: Mapping[Any, Any], keys: tuple[str, ...], what: str) -> None:
    """Refuse (:class:`AgentFileError` naming ``path`` and the key) a key of ``document`` not in ``keys``."""
    unknown = sorted(shown(key) for key in document if key not in keys)
    if unknown:
        raise AgentFileError(
            f"agent file {path}: its {what} holds a key {unknown[0]}, which no agent file has (its keys are {', '.join(keys)})"
        )


def _zip_members(path: Path, data: bytes, most: int = MAX_MEMBERS, where: str = "") -> list[zipfile.ZipInfo]:
    """The members of the zip ``data`` (the agent file ``path``, or its member ``where``), read from
    its directory (:func:`~empathy_zoo.safe_data.zip_members`), else :class:`AgentFileError`."""
    try:
        return zip_members(io.BytesIO(data), len(data), most)
    except ValueError as error:
        why = one_line(str(error), MESSAGE_CHARS)
        if where:
            raise AgentFileError(f"agent file {path}: its member {where} is no archive of torch.save ({why})") from None
        raise AgentFileError(f"{path} is not an empathy-zoo agent file ({why})") from None


def _check_library_zip(path: Path, members: list[zipfile.ZipInfo]) -> None:
    """A library's zip of its members (:data:`LIBRARY_MEMBERS`) only, each stored or deflated and
    not encrypted, together no larger once expanded than the agent file's size cap; else
    :class:`AgentFileError` naming the file and the member."""
    budget = CAPS["agent file"]
    for info in members:
        if info.filename not in LIBRARY_MEMBERS:
            raise AgentFileError(
                f"agent file {path} holds a member {info.filename[:100]!r}, which no agent file of "
                f"{', '.join(_LIBRARIES)} has (its members are {', '.join(LIBRARY_MEMBERS)})"
            )
        stored = info.compress_type == zipfile.ZIP_STORED and info.file_size == info.compress_size
        if not (stored or info.compress_type == zipfile.ZIP_DEFLATED) or info.flag_bits & 0x1:
            raise AgentFileError(
                f"agent file {path}: its member {info.filename} is compressed with method {info.compress_type} "
                f"({info.compress_size:,} bytes in the file for {info.file_size:,} once read) or encrypted; "
                "a member of an agent file is stored or deflated"
            )
    total = sum(info.file_size for info in members)
    if total > budget:
        raise AgentFileError(
            f"agent file {path}: its members expand to {total:,} bytes, more than the {budget:,} bytes an agent "
            "file may hold (docs/limits.md); refusing to decompress them"
        )


def _check_library_tensors(path: Path, archive: zipfile.ZipFile) -> None:
    """Each ``.pth`` member of a library's ``archive`` a ``torch.save`` zip (stored records only,
    :func:`~empathy_zoo.safe_data.torch_zip_problem`), and ``pytorch_variables.pth`` one of ``{}``;
    else :class:`AgentFileError` naming the file and the member. (Read one at a time: the library
    reads each again.)"""
    for name in archive.namelist():
        if not name.endswith(".pth"):
            continue
        data = archive.read(name)
        problem = torch_zip_problem(_zip_members(path, data, where=name), len(data))
        if problem:
            raise AgentFileError(f"agent file {path}: its member {name} is no archive of torch.save ({problem})")
        if name == "pytorch_variables.pth":
            try:
                variables = torch.load(io.BytesIO(data), map_location="cpu", weights_only=True)
            except Exception as error:  # (torch raises several kinds for a damaged file)
                raise AgentFileError(f"agent file {path}: its member {name} cannot be read ({_why(error)})") from None
            if not isinstance(variables, dict) or variables:
                found = ", ".join(sorted(map(shown, variables))) if isinstance(variables, dict) else type(variables).__name__
                raise AgentFileError(
                    f"agent file {path}: its member {name} holds {found[:MESSAGE_CHARS]}; DQN and PPO keep no variables "
                    "there (it holds {})"
                )


def _checker(path: Path) -> DocumentChecker:
    """Checks of one agent file's header, each raising :class:`AgentFileError` naming ``path`` and the field."""
    return DocumentChecker(
        path,
        AgentFileError,
        "an agent file's header",
        "an agent of this suite",
        "move it away (train the run again to make it anew)",
    )


def _check_header_fields(path: Path, header: dict[str, Any], check: DocumentChecker | None = None) -> dict[str, Any]:
    """``header`` (plain data with :data:`HEADER_KEYS`, read from the agent file at ``path``) if each
    field a reader uses is what the trainer writes (the run's configuration, as its result file's
    ``config``): no key but :data:`HEADER_KEYS` and :data:`HEADER_OPTIONAL`; ``method`` a registered
    method's name by its shape (:data:`METHOD_NAME`; the registry sits above this module:
    :func:`empathy_zoo.experiment.agent_method.check_agent_method`) or a ``package.module:NAME``
    plug-in, kept as text and never imported; ``settings`` an object; ``env`` a registered
    environment and ``env_kwargs`` its arguments, within what it builds (as a result file's,
    :func:`~empathy_zoo.result_file.check_env_kwargs`); where present, ``run_id`` and ``variant``
    file-name-safe names, ``label`` a label, ``fixed`` agent names and policy labels (parsed as
    text, nothing resolved), ``seed``, ``steps``, ``eval_interval`` and ``eval_episodes`` within
    their bounds, ``reward`` and ``description`` plain data of finite numbers and printable text.
    Anything else raises :class:`AgentFileError` naming the file and the field (``check``'s error,
    where given: the writer's); nothing read from it is printed or built before."""
    check = check or _checker(path)
    for key in header:
        if key not in HEADER_KEYS and key not in HEADER_OPTIONAL:
            raise check.fail(
                f"header (the key {str(key)[:60]!r})",
                f"no such key (an agent file's header holds {', '.join((*HEADER_KEYS, *HEADER_OPTIONAL))})",
                key,
            )
    method = check.text(header["method"], "header.method")
    if len(method) > MAX_PLUGIN_NAME or not (METHOD_NAME.fullmatch(method) or PLUGIN_NAME.fullmatch(method)):
        raise check.fail(
            "header.method",
            "a registered method's name or a package.module:NAME plug-in (kept as text, never imported)",
            method,
        )
    check.table(header["settings"], "header.settings")
    env = check.name(header["env"], "header.env")
    if env not in ENGINES:
        raise check.fail("header.env", f"a registered environment ({', '.join(ENGINES)})", env)
    check_env_kwargs(check, env, header["env_kwargs"], "header.env_kwargs")
    if header.get("fixed") is not None:
        agents = ENGINES[env](1, **header["env_kwargs"]).agents  # (its arguments checked above)
        for agent, policy in check.table(header["fixed"], "header.fixed").items():
            check.name(agent, f"header.fixed (the agent {agent!r})")
            if agent not in agents[1:]:
                raise check.fail(
                    f"header.fixed (the agent {agent!r})", f"an other agent of {env} ({', '.join(agents[1:])})", agent
                )
            check.policy_label(policy, f"header.fixed.{agent}")
    for name in ("run_id", "variant"):
        if header.get(name) is not None:
            check.name(header[name], f"header.{name}")
    if header.get("label") is not None:
        check.label(header["label"], "header.label")
    bounds = {
        "seed": (0, MAX_SEED),
        "steps": (1, MAX_STEPS),
        "eval_interval": (1, MAX_STEPS),
        "eval_episodes": (1, MAX_EVAL_EPISODES),
    }
    for name, (low, high) in bounds.items():
        if header.get(name) is not None:
            check.integer(header[name], f"header.{name}", low, high)
    for name in ("reward", "description"):
        check.plain(header.get(name), f"header.{name}")
    return header


def _description(
    header: Mapping[str, Any], obs_size: int, num_actions: int, heads: list[str], acting: str, source: Mapping[str, str]
) -> dict[str, Any]:
    return {**header, "obs_size": obs_size, "num_actions": num_actions, "heads": heads, "acting": acting, **source}


def _library_member(path: Path, data: bytes, members: list[zipfile.ZipInfo]) -> dict[str, Any] | None:
    """The :data:`LIBRARY_MEMBER` of an agent file kept in a library's zip (checked by
    :func:`_read_member`, once its members are, by :func:`_check_library_zip`), or ``None`` when
    ``data`` (of ``members``) has no such member (a ``torch.save`` file is a zip too, without it).
    A damaged zip raises :class:`AgentFileError` naming the file."""
    if LIBRARY_MEMBER not in (info.filename for info in members):
        return None
    _check_library_zip(path, members)
    try:
        with zipfile.ZipFile(io.BytesIO(data)) as archive:
            return _read_member(path, archive)
    except _ZIP_ERRORS as error:
        raise AgentFileError(f"agent file {path} is a damaged zip ({_why(error)})") from None


def _json_member(path: Path, archive: zipfile.ZipFile, name: str) -> Any:
    """The JSON member ``name`` of a library's zip, at most :data:`MEMBER_BYTES` and nested no
    deeper than the bounded reader allows (``ValueError`` naming the agent file otherwise; a zip's
    own errors, a bad CRC, are the caller's to name)."""
    if name not in archive.namelist():
        raise AgentFileError(f"agent file {path} has no member {name!r}: it is not a whole agent file of its library")
    if archive.getinfo(name).file_size > MEMBER_BYTES:
        raise AgentFileError(f"agent file {path}: its member {name} is larger than {MEMBER_BYTES:,} bytes")
    data = archive.read(name)
    check_json_depth(data, f"agent file {path}: its member {name}")
    try:
        return parse_json(data)
    except (ValueError, RecursionError) as error:
        raise AgentFileError(f"agent file {path}: its {name} is corrupted ({one_line(str(error), MESSAGE_CHARS)})") from None


def _read_member(path: Path, archive: zipfile.ZipFile) -> dict[str, Any]:
    member = _json_member(path, archive, LIBRARY_MEMBER)
    _check_format(path, member)
    _check_keys(path, member, LIBRARY_MEMBER_KEYS, LIBRARY_MEMBER)
    if member.get("library") not in _LIBRARIES or member.get("algorithm") not in _LIBRARIES.get(member.get("library"), ()):
        raise AgentFileError(
            f"agent file {path} holds a {shown(member.get('library'))} {shown(member.get('algorithm'))} model, "
            "which this empathy-zoo does not read"
        )
    check = _checker(path)
    for name in ("obs_size", "num_actions"):
        check.integer(member.get(name), f"{LIBRARY_MEMBER}.{name}", 1, MAX_OBSERVATION)
    heads = member.get("heads")
    if not isinstance(heads, list) or not all(isinstance(head, str) and _HEAD_NAME.fullmatch(head) for head in heads):
        raise check.fail(f"{LIBRARY_MEMBER}.heads", "an array of head names (lower-case identifiers)", heads)
    acting = member.get("acting")
    if not (isinstance(acting, str) and _HEAD_NAME.fullmatch(acting)) or (heads and acting not in heads):
        raise check.fail(f"{LIBRARY_MEMBER}.acting", f"one of its heads {heads} (a policy's name without heads)", acting)
    check.text(member.get("policy"), f"{LIBRARY_MEMBER}.policy")
    try:
        header = _check_header(member.get("header"))
    except (ValueError, RecursionError) as error:
        raise AgentFileError(f"agent file {path} is malformed: {one_line(str(error), MESSAGE_CHARS)}") from None
    return {**member, "header": _check_header_fields(path, header)}


def _load_library_agent(path: Path, data: bytes, member: Mapping[str, Any], source: Mapping[str, str]) -> SB3Agent:
    """A Stable-Baselines3 agent file read with SB3's own ``load``, every pickled entry of its
    ``data`` replaced by an object built here (so nothing is unpickled: SB3 reads the networks with
    ``weights_only=True``)."""
    try:
        import stable_baselines3 as sb3
    except ImportError:
        raise ImportError(f"{path} is a Stable-Baselines3 agent: install it with {install_command('sb3')}") from None
    cls = getattr(sb3, member["algorithm"])
    if member["policy"] not in cls.policy_aliases:
        raise AgentFileError(
            f"agent file {path}: its {LIBRARY_MEMBER} names policy {shown(member['policy'])}; "
            f"{member['algorithm']} has {', '.join(cls.policy_aliases)}"
        )
    try:
        with zipfile.ZipFile(io.BytesIO(data)) as archive:
            saved = _json_member(path, archive, "data")
            if not isinstance(saved, dict):
                raise AgentFileError(f"agent file {path}: its member 'data' is a {type(saved).__name__}, not an object")
            custom = _sb3_custom_objects(cls, member, saved)
            pickled = sorted(key for key, value in saved.items() if isinstance(value, dict) and ":serialized:" in value)
            unknown = [key for key in pickled if key not in custom]
            if unknown:
                raise AgentFileError(
                    f"agent file {path} holds pickled objects {shown(unknown)} this loader does not rebuild; "
                    "refusing to unpickle them"
                )
            sizes = (int(member["obs_size"]), int(member["num_actions"]))
            check_sb3_data(_checker(path), member["algorithm"], saved, *sizes, len(data))
            _check_library_tensors(path, archive)
    except _ZIP_ERRORS as error:
        raise AgentFileError(f"agent file {path} is a damaged zip ({_why(error)})") from None
    try:
        model = cls.load(io.BytesIO(data), device="cpu", custom_objects=custom)
    except Exception as error:  # (SB3 and torch raise many kinds for a damaged zip)
        raise AgentFileError(f"agent file {path}: {member['library']} cannot load it ({_why(error)})") from None
    header = member["header"]
    description = _description(
        header, int(member["obs_size"]), int(member["num_actions"]), list(member["heads"]), member["acting"], source
    )
    description.update(library=member["library"], algorithm=member["algorithm"])
    return SB3Agent(model, member["heads"], member["acting"], description)


def _sb3_custom_objects(cls: Any, member: Mapping[str, Any], saved: Mapping[str, Any]) -> dict[str, Any]:
    """What replaces the pickled entries of an SB3 ``data`` file: the spaces the suite's SB3 learner
    builds (``Box(-inf, inf, (V,), float32)``, ``Discrete(A)``), the policy class by its alias, SB3's
    buffer classes, constant schedules and no last observations or episode buffers (they serve only
    training); the replay or rollout buffer is made one step long, of one environment
    (:data:`~empathy_zoo.sb3_agent_data.ACTING_ONLY`: a loaded agent only acts)."""
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
        **ACTING_ONLY,
    }
    return {key: value for key, value in custom.items() if key in saved}
