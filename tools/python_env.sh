#!/usr/bin/env bash
# Creates .venv with the Python packages the interop tests and the Python package's
# tests use, and maturin, which builds the package's wheel (idempotent).
set -euo pipefail
cd "$(dirname "$0")/.."
if [ ! -x .venv/bin/python ] || ! .venv/bin/python -c "import pytest" 2>/dev/null; then
  python3 -m venv .venv
  .venv/bin/pip install --quiet --upgrade pip
fi
if [ -f tests/python/requirements.txt ]; then
  .venv/bin/pip install --quiet -r tests/python/requirements.txt
fi
if [ -f python/requirements-test.txt ]; then
  .venv/bin/pip install --quiet -r python/requirements-test.txt
fi
