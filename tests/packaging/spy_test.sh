#!/usr/bin/env bash
# rdtf-spy starts Debian 12's lcm-spy with rdtf's jar and decodes rdtfd's channels.
# Runs inside a network namespace of its own (tests/support/in_netns.sh; LCM's multicast stays
# there): starts rdtfd on a copy of examples/models/arm3.gltf, then rdtf-spy under Xvfb
# (xvfb-run) with a probe agent (SpyProbe.java) that reads lcm-spy's channel table from inside its
# JVM and opens one message view (jchart2d). Checks that every channel kind below shows its rdtf
# type, that a message view opened, and that nothing failed to decode; takes a screenshot of the
# display (xwd) and keeps it as PNG in $RDTF_TEST_ARTIFACTS (default: the build's
# Testing/rdtf-spy.png) so a person can look at it.
# Usage: spy_test.sh RDTFD RDTF_SPY RDTF_LCM_JAR MODEL_DIR ARTIFACT_DIR
set -euo pipefail

rdtfd=$1 spy=$2 jar=$3 models=$4 artifacts=$5
here=$(cd "$(dirname "$0")" && pwd)
fail() { echo "FAIL: $*" >&2; exit 1; }
for tool in xvfb-run xwd javac jar python3; do
  command -v "$tool" >/dev/null || fail "$tool not installed (scripts/install-deps.sh)"
done
[[ -f $jar ]] || fail "no rdtf_lcmtypes.jar at '$jar' (javac or lcm.jar missing at configure time)"

work=$(mktemp -d)
daemon_pid=
cleanup() {
  [[ -n $daemon_pid ]] && kill "$daemon_pid" 2>/dev/null && wait "$daemon_pid" 2>/dev/null
  rm -rf "$work"
}
trap cleanup EXIT

# The channel kinds rdtfd sends for a model with the defaults (simulation on), without validation
# to be quick; each must show its type in lcm-spy's table.
# lcm-spy shows the class's simple name.
declare -A type_of=([STATUS]=status_t [MANIFEST]=manifest_t [DESCRIPTION]=description_t
                    [INERTIA]=inertia_table_t [JOINT_STATE]=joint_state_t [LINK_STATE]=link_state_t)
kinds=DESCRIPTION,STATUS,MANIFEST,INERTIA,JOINT_STATE,LINK_STATE

mkdir -p "$work/models" "$work/probe/classes"
cp "$models/arm3.gltf" "$models/arm3.bin" "$work/models/"
javac -nowarn -d "$work/probe/classes" "$here/SpyProbe.java"
printf 'Premain-Class: SpyProbe\n' >"$work/probe/manifest.txt"
jar cfm "$work/probe/probe.jar" "$work/probe/manifest.txt" -C "$work/probe/classes" .

"$rdtfd" --watch "$work/models" --output "$work/out" --no-validate --republish-ms 1000 \
  >"$work/rdtfd.log" 2>&1 &
daemon_pid=$!

# Inside xvfb-run: rdtf-spy in the background, wait for the probe's VIEW line (or the spy's end),
# screenshot the whole display, stop the spy. The spy's exit status is what it was when stopped.
cat >"$work/inside.sh" <<'INSIDE'
set -u
work=$1 spy=$2 jar=$3 kinds=$4
RDTF_LCM_JAR=$jar JDK_JAVA_OPTIONS="-javaagent:$work/probe/probe.jar=$kinds" "$spy" >"$work/spy.log" 2>&1 &
spy_pid=$!
deadline=$((SECONDS + 90))
# The probe prints its result line when the view shows; lcm-spy offers nothing to block on.
until grep -q '^VIEW' "$work/spy.log" || ! kill -0 "$spy_pid" 2>/dev/null || ((SECONDS > deadline)); do
  sleep 0.2
done
alive=no
kill -0 "$spy_pid" 2>/dev/null && alive=yes
echo "spy alive at screenshot: $alive" >"$work/inside.log"
xwd -root -silent >"$work/screen.xwd"
kill "$spy_pid" 2>/dev/null
wait "$spy_pid" 2>/dev/null
exit 0
INSIDE
xvfb-run -a -s "-screen 0 1280x800x24 -nolisten tcp" bash "$work/inside.sh" "$work" "$spy" "$jar" "$kinds"

echo "--- lcm-spy output"; grep -v '^ROW' "$work/spy.log" | head -40 || true
echo "--- lcm-spy table as the probe read it"; grep '^ROW' "$work/spy.log" | sort -u -k2,2 | head -40 || true
cat "$work/inside.log"

grep -q 'spy alive at screenshot: yes' "$work/inside.log" || fail "lcm-spy was not running when the view was awaited (see its output above)"
if grep -q 'Unrecognized option' "$work/spy.log"; then fail "the JVM refused an option"; fi
if grep -q 'Spy.messageReceived ex' "$work/spy.log"; then fail "lcm-spy failed to decode a message"; fi
if grep -q 'VIEW-ERROR' "$work/spy.log"; then fail "the message view did not open"; fi
grep -q '^VIEW lcm.spy.ObjectPanel' "$work/spy.log" || fail "no message view opened within 90 s"
for kind in "${!type_of[@]}"; do
  grep -Eq "^ROW RDTF/([^ ]+/)?$kind ${type_of[$kind]} [1-9]" "$work/spy.log" ||
    fail "channel kind $kind not shown decoded as ${type_of[$kind]}"
done
# lcm-spy's last column counts the messages of a channel it could not decode.
if grep '^ROW' "$work/spy.log" | grep -v ' undecodable=0$'; then fail "lcm-spy counted undecodable messages"; fi

mkdir -p "$artifacts"
python3 "$here/xwd_to_png.py" "$work/screen.xwd" "$artifacts/rdtf-spy.png"
echo "PASS: lcm-spy decoded ${kinds//,/ }; screenshot $artifacts/rdtf-spy.png"
