"""Peak resident memory of writing and of loading one ensemble's checkpoint, for one env's share
of the paper profile (25 runs, replay memories of 500,000 transitions, filled).

Each phase runs in a fresh process (the peak, ``VmHWM``, cannot go down within one):

* ``save``: build the learner as the runner does, fill every replay memory, then write the
  checkpoint with the runner's ``save_checkpoint`` — reports the resident memory before the write
  and the peak during it;
* ``load``: build a fresh learner (what a resumed sweep does), then ``load_checkpoint`` and
  ``load_state_dict`` — reports the peak.

    python benchmarks/checkpoint_memory.py                   # this checkout
    python benchmarks/checkpoint_memory.py --tree /tmp/old   # another tree, e.g.
                                                             # `git archive REV | tar -x -C /tmp/old`

Linux only (reads ``/proc/self/status``).
"""

from __future__ import annotations

import argparse
import re
import subprocess
import sys
import tempfile
from pathlib import Path

RUNS = 25
CAPACITY = 500_000
MB = 2**20


def _status(field: str) -> int:
    """A ``/proc/self/status`` figure in bytes."""
    match = re.search(rf"^{field}:\s+(\d+) kB", Path("/proc/self/status").read_text(), re.MULTILINE)
    assert match, field
    return int(match.group(1)) * 1024


def _learner():  # the tree's own Learner type
    import torch

    from empathy_zoo.experiment.model import RunSpec
    from empathy_zoo.vector import VectorEnv

    torch.set_num_threads(1)
    betas = [0.75, 0.5, 0.25] * 5 + [1.0] * 10
    specs = [
        RunSpec.of(env="coexistence_v0", seed=i, settings={"selfishness": beta, "replay_capacity": CAPACITY})
        for i, beta in enumerate(betas[:RUNS])
    ]
    venv = VectorEnv("coexistence_v0", 1)
    method = specs[0].method_object()
    return method.learner([s.method_settings() for s in specs], [s.seed for s in specs], venv.obs_size, venv.num_actions, "cpu")


def phase(name: str, path: Path) -> None:
    import torch

    from empathy_zoo.training.checkpoint import load_checkpoint, save_checkpoint

    learner = _learner()
    replay = learner.replay
    if name == "save":
        generator = torch.Generator().manual_seed(0)
        for buffer in (replay.observations, replay.flags):
            buffer.random_(0, 200, generator=generator)
        replay.reward.uniform_(generator=generator)
        replay.position, replay.size = 0, replay.capacity
        before = _status("VmRSS")
        save_checkpoint(path, {"learner": learner.state_dict()})
        print(
            f"save: resident before {before / MB:,.0f} MB, peak during the write {_status('VmHWM') / MB:,.0f} MB "
            f"(+{(_status('VmHWM') - before) / MB:,.0f} MB); checkpoint {path.stat().st_size / MB:,.0f} MB"
        )
    else:
        before = _status("VmRSS")
        learner.load_state_dict(load_checkpoint(path)["learner"])
        assert replay.size == replay.capacity
        print(
            f"load: resident with a fresh learner {before / MB:,.0f} MB, peak while loading "
            f"{_status('VmHWM') / MB:,.0f} MB (+{(_status('VmHWM') - before) / MB:,.0f} MB)"
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tree", help="import the suite from this source tree instead of the installed one")
    parser.add_argument("--phase", choices=["save", "load"], help=argparse.SUPPRESS)
    parser.add_argument("--path", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.tree:  # bypass the editable install's finder so that the other tree's modules load
        sys.meta_path[:] = [finder for finder in sys.meta_path if "ditable" not in type(finder).__name__]
        sys.path.insert(0, args.tree)
    if args.phase:
        phase(args.phase, Path(args.path))
        return
    sys.path.insert(0, str(Path(__file__).parent))
    from machine import describe_machine

    print("\n".join(describe_machine()))
    print(
        f"one ensemble of {RUNS} runs (Coexistence, the paper's β mix), replay {CAPACITY:,} transitions per run, "
        f"tree: {args.tree or 'this checkout'}"
    )
    with tempfile.TemporaryDirectory(prefix="ez-ckpt-mem-") as tmp:
        path = Path(tmp) / "ensemble.pt"
        for name in ("save", "load"):
            command = [sys.executable, __file__, "--phase", name, "--path", str(path)]
            subprocess.run(command + (["--tree", args.tree] if args.tree else []), check=True)
    print("command: python benchmarks/checkpoint_memory.py" + (f" --tree {args.tree}" if args.tree else ""))


if __name__ == "__main__":
    main()
