"""Batched engines: the rules of every environment, written once, stepping N environments."""

from empathy_zoo.engine.base import GridEngine, StepEvents
from empathy_zoo.engine.coexistence import CoexistenceEngine
from empathy_zoo.engine.sharing import SharingEngine

ENGINES: dict[str, type[GridEngine]] = {
    "coexistence_v0": CoexistenceEngine,
    "sharing_v0": SharingEngine,
}
"""Engine class of every registered environment, by environment name."""

__all__ = ["ENGINES", "GridEngine", "StepEvents", "CoexistenceEngine", "SharingEngine"]
