#!/usr/bin/env bash
# Installs every build and run dependency of rsw from Debian 12 packages.
# Idempotent: apt-get skips what is already installed. Run as root (or with sudo).
# Nothing is downloaded at build time; this script is the only install step.
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config git
  libeigen3-dev            # dense/sparse linear algebra
  libsuitesparse-dev       # CHOLMOD, UMFPACK, KLU direct solvers
  libopenblas0-serial      # optimised BLAS/LAPACK under SuiteSparse (replaces reference BLAS)
  libsundials-dev          # KINSOL's Anderson-accelerated fixed point (electro-thermal coupling), SPFGMR (GMRES)
  libvtk9-dev              # .vtu/.vtm/.pvd output and read-back in tests
  libhdf5-dev hdf5-tools   # results.h5 and h5dump
  libgtest-dev libgmock-dev
  libyaml-cpp-dev          # config files
  libcli11-dev             # command line
  nlohmann-json3-dev       # summary.json, schema dump
  libnlopt-cxx-dev         # optimiser for GP hyperparameters
  libudunits2-dev          # unit suffixes in config values (8 kA, 1.0 mm)
  python3-matplotlib python3-h5py python3-numpy   # plot scripts (/usr/bin/python3)
  python3-jsonschema python3-yaml   # test of the case file's JSON Schema
  libopenmpi-dev openmpi-bin   # studies over MPI ranks (rsw study run under mpirun)
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#packages[@]} Debian packages already installed"
  exit 0
fi

SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "setup: run as root (apt-get needs it)" >&2; exit 1; }
  SUDO=sudo
fi
echo "setup: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
echo "setup: done"
