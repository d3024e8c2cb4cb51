#!/usr/bin/env bash
# Runs every test of the workspace. GPU tests need a Vulkan adapter: lavapipe is
# installed when none exists, so no GPU test can pass by skipping.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/ensure-vulkan.sh
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp}"
cargo test --workspace --all-targets --no-fail-fast "$@"
# The doctests (not among --all-targets): the graph's entry points, run on the adapter.
cargo test --workspace --doc --no-fail-fast "$@"
