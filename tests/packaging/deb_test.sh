#!/usr/bin/env bash
# cpack -G DEB builds rdtf's .deb from the build, which is unpacked into a scratch root with
# dpkg-deb -x (nothing is installed on this system): the package must hold rdtfd, the clients,
# rdtf-spy and the LCM types jar, the systemd unit (naming /usr/bin/rdtfd and /etc/rdtf/rdtfd.json),
# the config (a conffile) and librdtf with its headers and CMake package; and `rdtf --version`
# and `rdtfd --version` run from the scratch root print what the build's own binaries print; the
# packaged rdtf-spy finds the packaged jar; the packaged rdtf-view serves the packaged page, which
# loads whole in chromium.
# Usage: deb_test.sh BUILD_DIR
set -euo pipefail

build=$(cd "$1" && pwd)
fail() { echo "FAIL: $*" >&2; exit 1; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

(cd "$work" && cpack --config "$build/CPackConfig.cmake" -G DEB -B "$work/out" >"$work/cpack.log" 2>&1) ||
  { cat "$work/cpack.log"; fail "cpack -G DEB failed"; }
debs=("$work"/out/*.deb)
[[ ${#debs[@]} -eq 1 && -f ${debs[0]} ]] || fail "expected one .deb in $work/out, found: ${debs[*]}"
deb=${debs[0]}
echo "--- $(basename "$deb")"
dpkg-deb -f "$deb" Package Version Architecture Depends Recommends
dpkg-deb -x "$deb" "$work/root"

for file in usr/bin/rdtf usr/bin/rdtfd usr/bin/rdtf-echo usr/bin/rdtf-pd-controller usr/bin/rdtf-spy usr/bin/rdtf-view \
            usr/share/rdtf/view/index.html usr/share/rdtf/view/node_modules/three/build/three.module.js \
            usr/share/rdtf/java/rdtf_lcmtypes.jar usr/lib/systemd/system/rdtfd.service etc/rdtf/rdtfd.json \
            usr/lib/librdtf.a usr/include/rdtf/convert.h usr/include/rdtf/version.h \
            usr/lib/cmake/rdtf/rdtfConfig.cmake usr/lib/cmake/rdtf/rdtfTargets.cmake; do
  [[ -f $work/root/$file ]] || fail "the package has no /$file"
done
for program in rdtf rdtfd rdtf-echo rdtf-pd-controller rdtf-spy rdtf-view; do
  [[ -x $work/root/usr/bin/$program ]] || fail "/usr/bin/$program is not executable"
done
grep -qx 'ExecStart=/usr/bin/rdtfd --config /etc/rdtf/rdtfd.json' "$work/root/usr/lib/systemd/system/rdtfd.service" ||
  fail "the unit's ExecStart: $(grep ExecStart "$work/root/usr/lib/systemd/system/rdtfd.service")"
unit=$work/root/usr/lib/systemd/system/rdtfd.service
grep -qx 'User=rdtf' "$unit" || fail "the unit does not run rdtfd as the user rdtf"
grep -q 'source checkout\|scripts/run.sh' "$unit" "$work/root/etc/rdtf/rdtfd.json" &&
  fail "the installed unit or config still speaks of the source checkout"
dpkg-deb --ctrl-tarfile "$deb" | tar -xO ./postinst | grep -q 'adduser --system --group' ||
  fail "the postinst does not make the user rdtf"
# The unit as systemd reads it (ExecStart pointed at the unpacked binary), and its exposure: the
# sandbox of docs/security.md (9.0 "UNSAFE" before it), at most 2.5 of 10.
sed "s#/usr/bin/rdtfd#$work/root/usr/bin/rdtfd#" "$unit" > "$work/rdtfd.service"
verify=$(systemd-analyze verify "$work/rdtfd.service" 2>&1) || fail "systemd-analyze verify: $verify"
[[ -z $verify ]] || fail "systemd-analyze verify: $verify"
exposure=$(systemd-analyze security --offline=yes "$work/rdtfd.service" 2>&1 | sed -n 's/.*Overall exposure level for rdtfd.service: \([0-9.]*\).*/\1/p')
echo "unit exposure (systemd-analyze security): $exposure"
awk -v e="$exposure" 'BEGIN { exit !(e != "" && e <= 2.5) }' || fail "the unit's exposure is $exposure, above 2.5"
grep -q '"/var/lib/rdtf/models"' "$work/root/etc/rdtf/rdtfd.json" || fail "the config does not watch /var/lib/rdtf/models"
grep -q '"output": "/var/lib/rdtf/output"' "$work/root/etc/rdtf/rdtfd.json" || fail "the config's output is not /var/lib/rdtf/output"
dpkg-deb --ctrl-tarfile "$deb" | tar -xO ./conffiles | grep -qx /etc/rdtf/rdtfd.json || fail "rdtfd.json is not a conffile"
depends=$(dpkg-deb -f "$deb" Depends)
for lib in libode libssl libglib; do
  [[ $depends == *"$lib"* ]] || fail "Depends lacks $lib (dpkg-shlibdeps): $depends"
done

declare -A built_at=([rdtf]=clients/rdtf [rdtfd]=daemon [rdtf-echo]=clients/echo [rdtf-view]=clients/view
                      [rdtf-pd-controller]=clients/controller)
for program in rdtf rdtfd rdtf-echo rdtf-view rdtf-pd-controller; do
  packaged=$("$work/root/usr/bin/$program" --version)
  built=$("$build/${built_at[$program]}/$program" --version)
  echo "$program from the package: $packaged"
  [[ $packaged =~ ^$program\ [0-9]+\.[0-9]+\.[0-9]+\ \(commit\ ([0-9a-f]{7,40}(-dirty)?|unknown)\)$ ]] ||
    fail "$program --version printed '$packaged'"
  [[ $packaged == "$built" ]] || fail "$program --version: package '$packaged', build '$built'"
done
# The packaged rdtf-spy finds the packaged jar by itself (without it, it stops before lcm-spy
# starts); lcm-spy --help prints its usage and exits without opening a window.
spy_help=$(env -u RDTF_LCM_JAR "$work/root/usr/bin/rdtf-spy" --help 2>&1 || true)
[[ $spy_help == *"usage: lcm-spy"* ]] || fail "the packaged rdtf-spy did not start lcm-spy: $spy_help"
# The packaged rdtf-view serves the packaged page, not the build's source tree: its default
# --web-dir is the page beside it, and chromium loads that page with every module it imports
# (tools/view-test/page_loads.mjs), rdtf-view in a network namespace of its own.
repo=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
view_dir=$(realpath "$work/root/usr/share/rdtf/view")  # as rdtf-view finds it from /proc/self/exe
"$work/root/usr/bin/rdtf-view" --help | grep -qF -- "--web-dir TEXT=$view_dir" ||
  fail "the packaged rdtf-view does not serve $view_dir: $("$work/root/usr/bin/rdtf-view" --help | grep -- --web-dir)"
"$repo/tests/support/in_netns.sh" bash -c '
  "$1" --port 18765 --lcm-url "udpm://239.255.76.67:7667?ttl=0" > "$2/view.log" 2>&1 &
  view=$!
  for _ in $(seq 100); do grep -q "http://" "$2/view.log" && break; sleep 0.1; done
  node "$3/tools/view-test/page_loads.mjs" http://127.0.0.1:18765/
  status=$?
  kill "$view"; wait "$view" 2>/dev/null
  exit "$status"' page "$work/root/usr/bin/rdtf-view" "$work" "$repo" ||
  fail "chromium did not load the packaged page whole (rdtf-view: $(cat "$work/view.log"))"
echo "PASS: $(basename "$deb") holds the daemon, clients, rdtf-view and its page, unit, config and library; rdtf --version runs from it"
