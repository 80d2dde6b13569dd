#!/usr/bin/env bash
# cmake/RdtfVersion.cmake (what `rdtf --version` and `rdtfd --version` print) in each situation:
# a git checkout (its HEAD, "-dirty" with uncommitted changes), a source tree that is no checkout
# (GIT_COMMIT file, else "unknown"), and no rewrite when nothing changed (so nothing recompiles).
# Usage: version_fallback_test.sh cmake/RdtfVersion.cmake
set -euo pipefail

script=$1
fail() { echo "FAIL: $*" >&2; exit 1; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
export GIT_CEILING_DIRECTORIES=$work  # the scratch tree is never taken for part of another checkout

commit_of() {
  cmake -DSOURCE_DIR="$work/src" -DOUTPUT="$work/version.cc" -DVERSION=1.2.3 -P "$script"
  grep -q 'const char\* version() { return "1.2.3"; }' "$work/version.cc" || fail "version not 1.2.3: $(cat "$work/version.cc")"
  sed -n 's/.*git_commit() { return "\(.*\)"; }.*/\1/p' "$work/version.cc"
}
expect() {
  local got
  got=$(commit_of)
  [[ $got == "$1" ]] || fail "$2: commit '$got', expected '$1'"
  echo "ok: $2: $got"
}

mkdir -p "$work/src"
echo 'int x;' >"$work/src/a.cc"
expect unknown "no checkout, no GIT_COMMIT file"
echo 'abcdef123456' >"$work/src/GIT_COMMIT"
expect abcdef123456 "no checkout, GIT_COMMIT file"
echo 'not a commit; rm -rf /' >"$work/src/GIT_COMMIT"
expect unknown "no checkout, GIT_COMMIT file with other text"
rm "$work/src/GIT_COMMIT"

git -C "$work/src" init -q
git -C "$work/src" add a.cc
git -C "$work/src" -c user.name=t -c user.email=t@t commit -q -m one
head=$(git -C "$work/src" rev-parse --short=12 HEAD)
expect "$head" "clean checkout"
touch -d '2000-01-01' "$work/version.cc"
before=$(stat -c %y "$work/version.cc")
commit_of >/dev/null
[[ $(stat -c %y "$work/version.cc") == "$before" ]] || fail "version.cc rewritten though nothing changed"
echo "ok: unchanged commit: version.cc not rewritten"
echo 'int y;' >>"$work/src/a.cc"
expect "$head-dirty" "checkout with uncommitted changes"
echo "PASS"
