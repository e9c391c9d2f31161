#!/usr/bin/env bash
# Installs the Debian 12 (bookworm) packages centridem needs to build, test and format, and only
# those that are missing: a second run finds everything installed and does nothing.
#
# Usage:  bash scripts/setup.sh        (as root, or as a user with sudo)
# `make setup` (and so `make build`, `make test`, `make demo`) runs it once per change of this file.
set -euo pipefail

# Compiler and build tools (OpenMP comes with g++ as libgomp), the libraries, the test and
# benchmark frameworks, and clang-format for `make format`.
packages=(
  build-essential cmake g++ pkg-config
  libtomlplusplus-dev libcli11-dev libfmt-dev nlohmann-json3-dev libnlopt-cxx-dev
  libcairo2-dev libeigen3-dev zlib1g-dev libxsimd-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  clang-format
  python3-vtk9 # VTK's own reader checks the ParaView files in a test (/usr/bin/python3)
)

say() { printf 'setup.sh: %s\n' "$*"; }
die() {
  printf 'setup.sh: error: %s\n' "$*" >&2
  exit 1
}

if ! command -v dpkg-query >/dev/null 2>&1 || ! command -v apt-get >/dev/null 2>&1; then
  die "dpkg-query/apt-get not found: this script supports Debian 12 (bookworm). Install these packages (or their equivalents) by hand: ${packages[*]}"
fi

if [[ -r /etc/os-release ]]; then
  # shellcheck source=/dev/null
  codename=$(. /etc/os-release && printf '%s' "${VERSION_CODENAME:-}")
  [[ $codename == bookworm ]] ||
    say "warning: this is '${codename:-unknown}', not Debian 12 (bookworm); trying anyway"
fi

# Prints those of the given packages that dpkg does not report fully installed ("ii").
not_installed() {
  local p status
  for p in "$@"; do
    # shellcheck disable=SC2016 # ${db:Status-Abbrev} is a dpkg-query field, not a shell expansion
    status=$(dpkg-query -W -f='${db:Status-Abbrev}' "$p" 2>/dev/null || true)
    [[ $status == ii* ]] || printf '%s\n' "$p"
  done
}

mapfile -t missing < <(not_installed "${packages[@]}")

if ((${#missing[@]} == 0)); then
  say "all ${#packages[@]} required packages are installed; nothing to do"
  exit 0
fi
say "missing packages: ${missing[*]}"

if ((EUID == 0)); then
  as_root=()
elif command -v sudo >/dev/null 2>&1; then
  as_root=(sudo)
  say "not root: using sudo"
else
  die "installing needs root and sudo is not available. Run as root:  bash scripts/setup.sh  (or: apt-get update && apt-get install -y --no-install-recommends ${missing[*]})"
fi

apt_get() { "${as_root[@]}" env DEBIAN_FRONTEND=noninteractive apt-get "$@"; }

say "apt-get update"
apt_get update ||
  die "apt-get update failed. Check that this machine reaches a Debian mirror (see /etc/apt/sources.list and /etc/apt/sources.list.d/) and that no other apt/dpkg process holds the lock, then run this script again."

say "apt-get install ${missing[*]}"
apt_get install -y --no-install-recommends "${missing[@]}" ||
  die "apt-get install failed for: ${missing[*]}. Read apt's message above (unknown package: not Debian 12 or a sources.list without 'main'; lock: another apt/dpkg is running), fix it, and run this script again."

# Confirm: apt may succeed without installing what was asked (held packages, for instance).
mapfile -t still < <(not_installed "${missing[@]}")
((${#still[@]} == 0)) || die "still not installed after apt-get install: ${still[*]}"
say "installed ${#missing[@]} package(s); all ${#packages[@]} required packages are present"
