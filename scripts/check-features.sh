#!/usr/bin/env bash
# Builds what a host that wants less gets: the library without its default features
# (no pipeline-file parser, no dumps, no asset baker or mesh loaders: METIS and
# meshoptimizer stay out), and the scene crate's tests without its builder. Metal and
# DX12 are built too, as far as this platform compiles them (their backends are
# target-gated in wgpu: nothing of them is tested here).
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build -p meshlight --no-default-features --features vulkan
cargo build -p meshlight-graph --no-default-features --features metal,dx12
cargo test -p meshlight-scene --no-default-features --lib
echo "the library builds without its default features"
