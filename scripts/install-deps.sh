#!/usr/bin/env bash
# Installs everything rdtf needs to build and test on Debian 12 (bookworm): Debian packages
# (installs only the missing ones; runs `apt-get update` only when something is missing) and the
# npm packages of tools/gltf-validator, tools/encoders, clients/view/web and tools/view-test (each
# skipped when its node_modules already matches its lock file).
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
  libdraco-dev libmeshoptimizer-dev draco
  liburdfdom-dev liburdfdom-tools libode-dev libmujoco-dev libassimp-dev
  libgtest-dev libgmock-dev libbenchmark-dev libcli11-dev libglib2.0-dev libssl-dev
  clang libclang-rt-14-dev
  iproute2 util-linux strace systemd
  default-jre libjchart2d-java xvfb xauth x11-apps dpkg-dev
  blender python3-numpy
  libboost-dev chromium
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

# --- liblcm and libdraco, patched ----------------------------------------------------------------
# Two Debian libraries are built from Debian's source of the installed version with rdtf's patches
# (scripts/<name>/*.patch), by CMake, with the build's sanitizer and fuzzer instrumentation:
# - liblcm 1.3.1's UDP receive path writes out of bounds on a crafted fragment (docs/security.md);
#   rdtfd and the clients link it statically. Kept in $RDTF_LCM_SRC (default /opt/rdtf/lcm-src;
#   CMake's RDTF_LCM_SOURCE_DIR).
# - libdraco 1.5.5's texture-coordinate decoders size a table and a loop from a count in the stream
#   (up to 256 MB and 2^31 steps from a few hundred bytes: docs/format.md, "Draco"); librdtf holds
#   the decoder's objects. Kept in $RDTF_DRACO_SRC (default /opt/rdtf/draco-src; CMake's
#   RDTF_DRACO_SOURCE_DIR): its src/ and LICENSE only.
# Each is done again only when its patches or the installed version change; the stamp
# .rdtf-patched is what CMake checks (cmake/PatchedSource.cmake).

# patched_source NAME SOURCE_PACKAGE INSTALLED_PACKAGE ROOT KEEP...: Debian's source of
# SOURCE_PACKAGE at INSTALLED_PACKAGE's version, scripts/NAME/*.patch applied, its paths KEEP (all
# when none are named) in ROOT.
patched_source() {
  local name=$1 source_package=$2 installed_package=$3 root=$4
  shift 4
  local version want work src_list keep
  version=$(dpkg-query -W -f='${Version}' "$installed_package")
  want=$( (echo "$version"; cat scripts/"$name"/*.patch) | sha256sum | cut -d' ' -f1)
  if [[ -f $root/.rdtf-patched && $(cat "$root/.rdtf-patched") == "$want" ]]; then
    say "$name: patched source in $root matches, nothing to do"
    return 0
  fi
  # `apt-get source` needs a deb-src entry: one for bookworm's main, added once.
  src_list=/etc/apt/sources.list.d/rdtf-deb-src.sources
  if ! grep -rqsE '^(Types:.*deb-src|deb-src )' /etc/apt/sources.list /etc/apt/sources.list.d/; then
    say "$name: adding $src_list (deb-src for bookworm main)"
    printf '%s\n' '# Added by rdtf scripts/install-deps.sh: sources of Debian packages rdtf patches (liblcm, libdraco).' \
      'Types: deb-src' 'URIs: http://deb.debian.org/debian' 'Suites: bookworm' 'Components: main' \
      'Signed-By: /usr/share/keyrings/debian-archive-keyring.gpg' | "${SUDO[@]}" tee "$src_list" >/dev/null
  fi
  say "$name: apt-get source $source_package=$version"
  apt_get update -q >/dev/null
  work=$(mktemp -d)
  # Root downloads into a folder _apt cannot enter: apt says so and downloads unsandboxed.
  if ! (cd "$work" && apt_get source -q --download-only "$source_package=$version" >/dev/null 2>"$work/apt.log"); then
    # Some mirrors serve the .orig tarball but not the .debian.tar.xz (seen here for lcm: 404).
    # The build then lacks debian/patches, which could not be checked for changes to lcm/*.c
    # (the installed changelog's entries, 1.3.1+repack1-2.1 to -3, name none; older ones are
    # cut): docs/security.md. apt has checked whatever it did download against the signed index.
    say "$name: apt-get source incomplete ($(grep -m1 '^E:' "$work/apt.log" || echo 'see apt'))"
  fi
  if compgen -G "$work/*.debian.tar.*" >/dev/null; then
    (cd "$work" && dpkg-source -q -x ./*.dsc src >/dev/null)
  elif compgen -G "$work/*.orig.tar.*" >/dev/null; then
    say "$name: using the .orig tarball alone (without Debian's patches: see docs/security.md)"
    mkdir "$work/src" && tar -xf "$work"/*.orig.tar.* -C "$work/src" --strip-components=1
  else
    say "$name: could not fetch Debian's source of $source_package $version" >&2
    cat "$work/apt.log" >&2
    exit 1
  fi
  for p in scripts/"$name"/*.patch; do
    say "$name: applying $p"
    patch -s -p1 -d "$work/src" <"$p"
  done
  if (($# == 0)); then
    mv "$work/src" "$work/keep"
  else
    for keep in "$@"; do
      mkdir -p "$work/keep/$(dirname "$keep")" && mv "$work/src/$keep" "$work/keep/$keep"
    done
  fi
  "${SUDO[@]}" mkdir -p "$(dirname "$root")"
  "${SUDO[@]}" rm -rf "$root.new"
  "${SUDO[@]}" cp -r "$work/keep" "$root.new"
  echo "$want" | "${SUDO[@]}" tee "$root.new/.rdtf-patched" >/dev/null
  "${SUDO[@]}" rm -rf "$root"
  "${SUDO[@]}" mv "$root.new" "$root"
  rm -rf "$work"
  say "$name: patched source of $source_package $version in $root"
}

patched_source lcm lcm liblcm-dev "${RDTF_LCM_SRC:-/opt/rdtf/lcm-src}"
patched_source draco draco libdraco-dev "${RDTF_DRACO_SRC:-/opt/rdtf/draco-src}" src LICENSE

# --- npm packages: tools/gltf-validator, tools/encoders (the encoders whose outputs
# tests/data/encoded/ holds: tests/data/encoded/make.sh rebuilds them), rdtf-view's three.js
# (clients/view/web) and its browser tests' puppeteer-core (tools/view-test) ------------------
# puppeteer-core downloads no browser: the tests drive Debian's chromium.
for folder in tools/gltf-validator tools/encoders clients/view/web tools/view-test; do
  [[ -f $folder/package.json ]] || continue
  stamp=$folder/node_modules/.rdtf-installed
  want=$(cat "$folder/package.json" "$folder/package-lock.json" 2>/dev/null | sha256sum | cut -d' ' -f1)
  if [[ -f $stamp && $(cat "$stamp") == "$want" ]]; then
    say "npm: $folder/node_modules matches the lock file, nothing to do"
  else
    if [[ -f $folder/package-lock.json ]]; then
      say "npm: npm ci in $folder"
      (cd "$folder" && npm ci --no-audit --no-fund --loglevel=error)
    else
      say "npm: npm install in $folder (no lock file)"
      (cd "$folder" && npm install --no-audit --no-fund --loglevel=error)
      want=$(cat "$folder/package.json" "$folder/package-lock.json" | sha256sum | cut -d' ' -f1)
    fi
    echo "$want" >"$stamp"
    say "npm: done"
  fi
done
