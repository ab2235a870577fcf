#!/usr/bin/env bash
# What the tests need on a fresh Debian machine: a Rust toolchain with rustfmt and clippy, and
# Debian's chromium (headless) for the report.html check.
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
# report.html is checked as headless Chromium renders it (tests/adapter.rs).
if ! command -v chromium >/dev/null 2>&1; then
  if command -v apt-get >/dev/null 2>&1; then
    SUDO=""
    if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
    export DEBIAN_FRONTEND=noninteractive
    $SUDO apt-get update
    $SUDO apt-get install -y --no-install-recommends chromium
  else
    echo "error: chromium missing and apt-get is not available; install it by hand" >&2
    exit 1
  fi
fi
chromium --version
