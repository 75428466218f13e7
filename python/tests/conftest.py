"""Shared helpers of the wheel's tests (python/tests): where the scenes and the CLI
binary are. The wheel itself is installed into the venv by tools/test_all.sh
(`maturin build` + `pip install`); these tests import it as a user would."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
SCENES = ROOT / "config" / "scenes"
BIN = Path(os.environ.get("DEVELOPABLE_SIM_BIN", ROOT / "target" / "release" / "developable_sim"))


def scene_path(name: str) -> Path:
    return SCENES / f"{name}.yaml"


def same_bits(a: np.ndarray, b: np.ndarray) -> bool:
    """Bit-identical arrays (same shape, dtype and bytes: -0.0 and NaN payloads count)."""
    a, b = np.ascontiguousarray(a), np.ascontiguousarray(b)
    return a.shape == b.shape and a.dtype == b.dtype and a.tobytes() == b.tobytes()


@pytest.fixture
def cli() -> Path:
    """The developable_sim binary that `cargo test --release` built."""
    assert BIN.is_file(), f"{BIN} missing: build it with cargo build --release (or set DEVELOPABLE_SIM_BIN)"
    return BIN
