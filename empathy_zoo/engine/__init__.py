"""Batched engines: the rules of every environment, written once, stepping N environments."""

from empathy_zoo.engine.base import GridEngine, StepEvents
from empathy_zoo.engine.coexistence import CoexistenceEngine
from empathy_zoo.engine.sharing import SharingEngine

__all__ = ["GridEngine", "StepEvents", "CoexistenceEngine", "SharingEngine"]
# (environments by name: empathy_zoo.environments)
