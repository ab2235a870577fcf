#!/usr/bin/env bash
# The external DEM codes the cross-code tests run: LAMMPS (lmp), LIGGGHTS (liggghts) and YADE
# (yade), from Debian's packages (see shared/external-codes.md for the versions), plus mpirun
# for `grainbench compare --np K`. Skips what is already installed.
set -euo pipefail
missing=()
command -v lmp >/dev/null 2>&1 || missing+=(lammps)
command -v liggghts >/dev/null 2>&1 || missing+=(liggghts)
command -v yade >/dev/null 2>&1 || missing+=(yade)
command -v mpirun >/dev/null 2>&1 || missing+=(openmpi-bin)
if [ ${#missing[@]} -eq 0 ]; then
  echo "external codes present: $(command -v lmp liggghts yade mpirun | tr '\n' ' ')"
  exit 0
fi
if ! command -v apt-get >/dev/null 2>&1; then
  echo "error: ${missing[*]} missing and apt-get is not available; install them by hand" >&2
  exit 1
fi
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update
$SUDO apt-get install -y --no-install-recommends "${missing[@]}"
command -v lmp liggghts yade mpirun
