#!/usr/bin/env bash
# What the tests need on a fresh Debian machine: a Rust toolchain with rustfmt and clippy.
# (The external DEM codes come from ci/install-externals.sh.)
set -euo pipefail
if ! command -v cargo >/dev/null 2>&1; then
  if command -v apt-get >/dev/null 2>&1; then
    apt-get update
    apt-get install -y --no-install-recommends ca-certificates curl build-essential
  fi
  curl -sSf https://sh.rustup.rs | sh -s -- -y --profile minimal -c rustfmt,clippy
  # shellcheck disable=SC1091
  . "$HOME/.cargo/env"
fi
rustup component add rustfmt clippy >/dev/null 2>&1 || true
cargo --version
