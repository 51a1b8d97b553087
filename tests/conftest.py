"""Test-wide settings: one torch thread per test process.

Tests train tiny networks; with several pytest workers, torch's default of one busy-waiting
thread per core oversubscribes the machine and small matmuls slow down by orders of magnitude.
"""

from __future__ import annotations

import torch

torch.set_num_threads(1)
