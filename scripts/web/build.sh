#!/usr/bin/env bash
# Builds mislab's web page into target/web/ (index.html, mislab_web.js, mislab_web_bg.wasm): the renderer and its
# shaders on the browser's WebGPU. Serve it with any static server: python3 -m http.server -d target/web
# Needs the wasm32 target (rustup target add wasm32-unknown-unknown) and wasm-bindgen-cli of the version Cargo.lock
# gives wasm-bindgen (cargo install wasm-bindgen-cli --version =<that>); nothing else is fetched.
set -euo pipefail
cd "$(dirname "$0")/../.."
version=$(grep -A1 '^name = "wasm-bindgen"$' Cargo.lock | sed -n 's/^version = "\(.*\)"/\1/p')
if ! command -v wasm-bindgen >/dev/null || [ "$(wasm-bindgen --version | cut -d' ' -f2)" != "$version" ]; then
    echo "scripts/web/build.sh needs wasm-bindgen-cli $version: cargo install wasm-bindgen-cli --version =$version" >&2
    exit 2
fi
# The release profile without debug info (the page downloads every byte); the shared target/ keeps the native build.
CARGO_PROFILE_RELEASE_DEBUG=false cargo build -p mislab-web --release --target wasm32-unknown-unknown
target=${CARGO_TARGET_DIR:-target}
rm -rf target/web
wasm-bindgen --target web --no-typescript --out-dir target/web "$target/wasm32-unknown-unknown/release/mislab_web.wasm"
cp web/index.html target/web/
du -h target/web/* | sed 's/^/  /'
echo "built target/web/ — serve it: python3 -m http.server -d target/web, then open http://localhost:8000"
