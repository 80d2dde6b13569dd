#!/usr/bin/env bash
# Installs everything rdtf needs to build and test on Debian 12 (bookworm): Debian packages
# (installs only the missing ones; runs `apt-get update` only when something is missing) and the
# npm packages of tools/gltf-validator (skipped when node_modules already matches the lock file).
# Idempotent: a second run installs nothing and takes well under a second.
# Run as root, or as a user who may use sudo.
set -euo pipefail

cd "$(dirname "${BASH_SOURCE[0]}")/.."
export DEBIAN_FRONTEND=noninteractive

say() { printf 'install-deps: %s\n' "$*"; }

PACKAGES=(
  build-essential cmake ninja-build pkg-config git
  nodejs npm
  liblcm-dev liblcm-bin liblcm-java default-jdk-headless
  libeigen3-dev nlohmann-json3-dev libtinygltf-dev libstb-dev
  liburdfdom-dev liburdfdom-tools libode-dev libmujoco-dev
  libgtest-dev libgmock-dev libbenchmark-dev libcli11-dev libglib2.0-dev libssl-dev
  clang libclang-rt-14-dev
  iproute2 util-linux
  blender python3-numpy
)

if [[ $(id -u) -eq 0 ]]; then
  SUDO=()
elif command -v sudo >/dev/null 2>&1; then
  SUDO=(sudo --preserve-env=DEBIAN_FRONTEND)
else
  SUDO=()
fi

installed() {
  [[ $(dpkg-query -W -f='${Status}' "$1" 2>/dev/null || true) == "install ok installed" ]]
}

# --- Debian packages ---------------------------------------------------------------------------
missing=()
for pkg in "${PACKAGES[@]}"; do
  case $pkg in
    # Node.js may come from another Debian-format source (the machine image ships NodeSource's
    # nodejs, which bundles npm and conflicts with Debian's npm package): only ask apt for them
    # when the commands are missing.
    nodejs) installed nodejs || command -v node >/dev/null 2>&1 || missing+=("$pkg") ;;
    npm) command -v npm >/dev/null 2>&1 || missing+=("$pkg") ;;
    *) installed "$pkg" || missing+=("$pkg") ;;
  esac
done

apt_get() {
  "${SUDO[@]}" apt-get -o DPkg::Lock::Timeout=600 -o Acquire::Retries=3 "$@"
}

if ((${#missing[@]} == 0)); then
  say "apt: all ${#PACKAGES[@]} Debian packages already installed, nothing to do"
else
  if [[ $(id -u) -ne 0 && ${#SUDO[@]} -eq 0 ]]; then
    say "apt: missing ${missing[*]}, but not root and no sudo: run this script as root" >&2
    exit 1
  fi
  say "apt: missing ${#missing[@]} package(s): ${missing[*]}"
  say "apt: apt-get update"
  apt_get update -q >/dev/null
  say "apt: apt-get install -y --no-install-recommends ${missing[*]}"
  if ! apt_get install -y -q --no-install-recommends "${missing[@]}"; then
    # One retry after a fresh update: a mirror can change under a stale list.
    say "apt: install failed, updating the package lists and trying once more"
    apt_get update -q >/dev/null
    apt_get install -y -q --no-install-recommends "${missing[@]}"
  fi
  say "apt: done"
fi

# --- npm packages of tools/gltf-validator ------------------------------------------------------
validator=tools/gltf-validator
if [[ -f $validator/package.json ]]; then
  stamp=$validator/node_modules/.rdtf-installed
  want=$(cat "$validator/package.json" "$validator/package-lock.json" 2>/dev/null | sha256sum | cut -d' ' -f1)
  if [[ -f $stamp && $(cat "$stamp") == "$want" ]]; then
    say "npm: $validator/node_modules matches the lock file, nothing to do"
  else
    if [[ -f $validator/package-lock.json ]]; then
      say "npm: npm ci in $validator"
      (cd "$validator" && npm ci --no-audit --no-fund --loglevel=error)
    else
      say "npm: npm install in $validator (no lock file)"
      (cd "$validator" && npm install --no-audit --no-fund --loglevel=error)
      want=$(cat "$validator/package.json" "$validator/package-lock.json" | sha256sum | cut -d' ' -f1)
    fi
    echo "$want" >"$stamp"
    say "npm: done"
  fi
fi
