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
set -euo pipefail
cd "$(dirname "$0")/.."

if [ "$#" -gt 0 ]; then
  for layer in "$@"; do
    cargo test --release -p "flatray-$layer"
  done
  exit 0
fi

if ! command -v chromium >/dev/null 2>&1 && [ -z "${FLATRAY_CHROMIUM:-}" ]; then
  echo "installing Chromium (Debian's package) for the browser test" >&2
  sudo=""
  [ "$(id -u)" = 0 ] || sudo="sudo"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq chromium
fi

export CARGO_TERM_COLOR="${CARGO_TERM_COLOR:-never}"

cargo test --release --workspace
# The Python package, built from source by pip, and its tests (a local
# two-worker Ray among them).
python3 -m pip install --quiet --disable-pip-version-check "./cli/python[test]"
python3 -m pytest cli/python/tests -q
# Again with only the code that runs on every processor (no AVX): the same
# images, plans and statistics are expected. (The docs' pictures and the
# slowest statistical tests, all run above, are left out here for time:
# the others, the agreement of path and light tracing on every example
# scene among them, check the portable kernel.)
FLATRAY_PORTABLE=1 cargo test --release -p flatray-geometry -p flatray-tests -- \
  --skip every_picture_in_the_docs_is_what_its_command_makes \
  --skip the_noise_estimate_ --skip the_relmse_estimate_ \
  --skip furnaces_of_arcs --skip round_rooms_and_columns \
  --skip the_memo_converges_at_corners --skip a_table_of_chosen_lights \
  --skip a_lasers_spot_on_a_wall
