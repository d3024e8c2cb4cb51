#!/usr/bin/env bash
# Renders the default scene (a procedural 1M-triangle mesh) into out/default.png, with the
# frame's graph and GPU timings in out/default.html.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/ensure-vulkan.sh
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp}"
cargo run --release -p meshlight-cli -- render -o out/default.png --html out/default.html "$@"
