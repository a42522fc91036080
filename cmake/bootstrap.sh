#!/usr/bin/env bash
# spinesim set-up on Debian 12 (run as root): installs the missing Debian packages,
# configures and builds, then either runs the default scene (`run`) or the default test
# suite (`test`). Idempotent: a second call installs nothing and rebuilds only what changed.
set -euo pipefail

usage() {
  echo "usage: bash cmake/bootstrap.sh run|test [extra ctest or spinesim-run arguments]" >&2
  exit 2
}
[[ $# -ge 1 ]] || usage
action=$1
shift

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${SPINESIM_BUILD_DIR:-$root/build}
jobs=${SPINESIM_JOBS:-$(nproc)}

# Debian packages the build, the tests and the plots need (by name, nothing downloaded).
packages=(
  cmake make ninja-build g++ ccache pkg-config
  libdeal.ii-dev          # deal.II 9.4 with Trilinos, p4est, PETSc, HDF5, MPI, TBB
  libopenblas0-serial     # optimised BLAS/LAPACK behind Debian's alternatives (single-threaded:
                          # no contention with OpenMP or MPI ranks); the dense eigenvalue
                          # solves of the step spectra run 4-5x faster than reference LAPACK
  openmpi-bin             # mpirun for the 2-rank tests
  libsuitesparse-dev      # CHOLMOD: the LSMFM's supernodal Cholesky
  libeigen3-dev libcli11-dev nlohmann-json3-dev libgtest-dev
  libinsighttoolkit5-dev  # CT volumes: NIfTI, NRRD, MetaImage readers
  zlib1g-dev              # checking that compressed CT data is complete
  libcgal-dev             # STL implant surfaces: reading, repair, point-in-solid queries
  gnuplot-nox             # PNG plots of studies and benchmarks
  clang-format            # the format-check target (.ci/run)
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "== installing Debian packages: ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

# OpenMPI refuses to start as root without these; the 2-core machines need oversubscribe.
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
export CCACHE_DIR=${CCACHE_DIR:-$root/.ccache}

mkdir -p "$build"
# Ninja for a new build directory: it compiles a target's files while the libraries it links
# are still building, where CMake's Makefiles wait for each dependency. A cold build of
# everything on 2 cores took 615 s with Ninja against 803-814 s with Makefiles. A directory
# configured before keeps its generator (CMake refuses to switch).
generator=()
[[ -f "$build/CMakeCache.txt" ]] || generator=(-G Ninja)
echo "== configuring ($build)"
cmake -S "$root" -B "$build" "${generator[@]}" -DCMAKE_BUILD_TYPE=Release >"$build/configure.log" 2>&1 ||
  { cat "$build/configure.log"; exit 1; }
# `run` builds only the executable and the libraries it loads (the first result comes sooner
# on a fresh machine); `test` builds everything.
targets=()
[[ "$action" == run ]] && targets=(--target spinesim)
echo "== building ${targets[*]:-everything} with $jobs jobs"
cmake --build "$build" -j "$jobs" "${targets[@]}"

case "$action" in
  run)
    out="$root/runs/default-$(date +%Y%m%d-%H%M%S)"
    echo "== running the default scene"
    "$build/bin/spinesim" run --output "$out" "$@"
    echo "== results: $out (summary.json, history.csv, log.txt, VTU/PVTU for ParaView)"
    ;;
  test)
    echo "== running the default test suite (benchmarks and known failures excluded)"
    # --no-tests=error: a configuration that lost its tests fails instead of passing empty.
    ctest --test-dir "$build" -LE "benchmark|known_failure|long" --output-on-failure \
      --no-tests=error -j "$jobs" "$@"
    ;;
  *) usage ;;
esac
