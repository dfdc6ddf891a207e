# Sourced by jobs/test.sh and jobs/run.sh: installs missing Debian packages (apt-get update once,
# then apt-get install -y), then configures and builds into build/ (incremental on a second call).
#   PFF_BUILD_DIR   build directory (default <repo>/build)
#   PFF_BUILD_TYPE  CMake build type (default Release)
#   PFF_CMAKE_ARGS  extra CMake arguments, e.g. "-DPFF_NATIVE=OFF"; with "-DPFF_PETSC64=ON" (PETSc with 64-bit
#                   indices, past 2^31 cells) Debian's libpetsc64-real-dev is installed too. Use another build
#                   directory for it: PFF_BUILD_DIR=build64 PFF_CMAKE_ARGS=-DPFF_PETSC64=ON bash jobs/test.sh
set -euo pipefail
PFF_ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
PFF_BUILD_DIR=${PFF_BUILD_DIR:-$PFF_ROOT/build}
PFF_BUILD_TYPE=${PFF_BUILD_TYPE:-Release}

PFF_PACKAGES="gcc g++ make cmake pkg-config git openmpi-bin libopenmpi-dev petsc-dev libhdf5-openmpi-dev libmetis-dev libyaml-dev libbullet-dev
  clang-format python3-h5py python3-numpy python3-matplotlib"
case " ${PFF_CMAKE_ARGS:-} " in
*-DPFF_PETSC64=ON*) PFF_PACKAGES="$PFF_PACKAGES libpetsc64-real-dev" ;;
esac

pff_install_packages() {
  local missing=()
  for p in $PFF_PACKAGES; do
    if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then missing+=("$p"); fi
  done
  [ ${#missing[@]} -eq 0 ] && return 0
  echo "pfflip: installing Debian packages: ${missing[*]}"
  local sudo=""
  [ "$(id -u)" -ne 0 ] && sudo="sudo"
  $sudo apt-get update
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y --no-install-recommends "${missing[@]}"
}

pff_build() {
  if [ ! -f "$PFF_BUILD_DIR/CMakeCache.txt" ]; then
    # shellcheck disable=SC2086
    cmake -S "$PFF_ROOT" -B "$PFF_BUILD_DIR" -DCMAKE_BUILD_TYPE="$PFF_BUILD_TYPE" ${PFF_CMAKE_ARGS:-}
  fi
  cmake --build "$PFF_BUILD_DIR" -j "$(nproc)"
}

# Open MPI refuses root and more ranks than cores unless told; our scripts and ctest always tell it.
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
PFF_MPIEXEC=(mpiexec --quiet --oversubscribe --bind-to none)

pff_install_packages
pff_build
