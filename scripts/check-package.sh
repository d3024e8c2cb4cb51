#!/usr/bin/env bash
# Checks that every library crate packages as `cargo publish` would package it (its
# metadata, its files, versions on its path dependencies), without building the packages
# or uploading anything. The applications and test helpers (`publish = false`) are left
# out, found from the manifests so a new crate is checked without being named here.
set -euo pipefail
cd "$(dirname "$0")/.."
private=$(cargo metadata --no-deps --format-version 1 |
    python3 -c 'import json,sys; print(" ".join("--exclude " + p["name"] for p in json.load(sys.stdin)["packages"] if p["publish"] == []))')
# shellcheck disable=SC2086 # one word per flag
cargo package --workspace $private --no-verify --allow-dirty --quiet
echo "every library crate packages"
