#!/usr/bin/env bash
# Fails when a library crate depends, directly or through another crate, on what only the
# applications may use: an argument parser (clap), a logger (env_logger) or a progress
# bar (indicatif: a library reports progress through a callback, and the application
# that owns the terminal draws it). Image files are the builder's business only: the
# texture decoders (png, zune-jpeg) come with meshlight-scene's `build` feature, and a
# renderer of baked assets takes neither (checked below). The library crates
# are the workspace members that can be published; the applications, the examples and
# the test helpers say `publish = false`. So a new pass crate is checked without being
# named here.
set -euo pipefail
cd "$(dirname "$0")/.."
FORBIDDEN='^(clap|env_logger|indicatif) '
members=$(cargo metadata --no-deps --format-version 1 |
    python3 -c 'import json,sys; print("\n".join(p["name"] for p in json.load(sys.stdin)["packages"] if p["publish"] != []))')
failed=0
checked=0
for crate in $members; do
    found=$(cargo tree -p "$crate" -e normal,build --prefix none --format '{p}' | grep -E "$FORBIDDEN" | sort -u || true)
    checked=$((checked + 1))
    if [ -n "$found" ]; then
        echo "$crate is a library crate but depends on: $(echo $found | tr '\n' ' ')" >&2
        echo "  move the code that needs it into an application crate under apps/" >&2
        failed=1
    fi
done
[ "$checked" -gt 0 ] || { echo "no library crates found" >&2; exit 1; }
# A renderer that only draws baked assets takes meshlight-scene without its `build`
# feature, and with it none of the builder's libraries.
BUILDER='^(meshopt|metis|tobj|gltf|draco-core|png|zune-jpeg|zune-core) '
found=$(cargo tree -p meshlight-scene --no-default-features -e normal,build --prefix none --format '{p}' |
    grep -E "$BUILDER" | sort -u || true)
if [ -n "$found" ]; then
    echo "meshlight-scene without default features depends on: $(echo $found | tr '\n' ' ')" >&2
    echo "  put the code that needs it behind the \`build\` feature" >&2
    failed=1
fi
[ "$failed" -eq 0 ] && echo "$checked library crates: no clap, env_logger or indicatif; meshlight-scene without \`build\`: no builder libraries (mesh loaders, simplifiers, image decoders)"
exit "$failed"
