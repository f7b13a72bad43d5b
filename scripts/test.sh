#!/usr/bin/env bash
# Runs every test of flatray on this machine, installing first what the
# tests need and the machine lacks: Chromium for the live view's browser
# test (Debian's package, with apt-get), and the Python package, built
# from source by pip with its test dependencies (maturin, NumPy, pytest,
# Ray). Needs the Rust toolchain and Python 3.9+ with pip.
#
#   scripts/test.sh
#
# Then: the workspace's tests in release mode, the Python package's
# tests, and the geometry and end-to-end tests again with only the code
# that runs on every processor (no AVX), which must give the same images.
#
# With names of the workspace's layers, only their tests (release mode,
# nothing installed):
#
#   scripts/test.sh geometry io
#
# Its three steps one by one, as CI runs them (`.ci/run`): Chromium's
# install, the workspace's tests, then the Python package's and the
# portable rerun:
#
#   scripts/test.sh --install
#   cargo test --release --workspace
#   scripts/test.sh --after-workspace
set -euo pipefail
cd "$(dirname "$0")/.."

steps="all"
case "${1:-}" in
  --install) steps="install" ;;
  --after-workspace) steps="after" ;;
  "") ;;
  *)
    for layer in "$@"; do
      cargo test --release -p "flatray-$layer"
    done
    exit 0
    ;;
esac

if [ "$steps" != "after" ] && ! command -v chromium >/dev/null 2>&1 && [ -z "${FLATRAY_CHROMIUM:-}" ]; then
  echo "installing Chromium (Debian's package) for the browser test" >&2
  sudo=""
  [ "$(id -u)" = 0 ] || sudo="sudo"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq chromium
fi

if [ "$steps" = "install" ]; then
  exit 0
fi

export CARGO_TERM_COLOR="${CARGO_TERM_COLOR:-never}"

if [ "$steps" = "all" ]; then
  cargo test --release --workspace
fi
# The Python package, built from source by pip, and its tests (a local
# two-worker Ray among them).
python3 -m pip install --quiet --disable-pip-version-check "./cli/python[test]"
python3 -m pytest cli/python/tests -q
# Again with only the code that runs on every processor (no AVX): every
# crate's unit tests (the geometry's kernels, the tracer's estimators),
# the geometry's property tests, and the end-to-end tests that render
# through every part of the pixel loop (every example scene with and
# without fast paths, path and light tracing, the closed forms, lines,
# memos, hard cases), which must give the same images, plans and
# statistics. The long statistical suites and the docs' pictures, run
# above, are not run again. `--workspace` keeps the features of every
# dependency as in the first run, so nothing is compiled again.
FLATRAY_PORTABLE=1 cargo test --release --workspace --lib \
  --test arc_roots --test properties \
  --test identity --test determinism --test hard_cases --test non_negative \
  --test exact_light --test circle_light --test square_light --test beams \
  --test aimed_mirror --test through_glass --test specular_runs --test glass \
  --test rough_mirror --test rough_glass --test light_tracing --test path_tracing \
  --test direct_light --test culling --test coherence --test lines --test onward \
  --test passes --test adaptive --test daylight --test snapshots
