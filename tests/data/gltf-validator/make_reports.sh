#!/bin/sh
# Regenerates the Khronos glTF validator's report (tools/gltf-validator) for every .gltf/.glb
# model below this folder, stored beside it as FILE.report.json (FILE keeps its extension:
# buffer/ has invalid_uri_data.gltf and invalid_uri_data.glb). The volatile "validatedAt" field is
# dropped, and this folder's absolute path is cut from messages, so that a report only changes
# when the validator's verdict does.
#
# When the validator cannot even start on a file (it throws "could not detect glTF format" on an
# empty file), the report holds {"uri", "fatalError": MESSAGE} instead of "issues": the test
# suite counts that as an error of the container.
set -eu
here=$(cd "$(dirname "$0")" && pwd)
validator="$here/../../../tools/gltf-validator/validate.mjs"
find "$here" -type f \( -name '*.gltf' -o -name '*.glb' \) | sort | while read -r model; do
  report="$model.report.json"
  status=0
  node "$validator" "$model" >"$report.out" 2>"$report.err" || status=$?
  if [ "$status" -eq 0 ] || [ "$status" -eq 3 ]; then
    jq --arg here "$here/" 'del(.validatedAt) | (.issues.messages[].message |= (split($here) | join("")))' \
      "$report.out" >"$report"
  elif [ -r "$model" ] && grep -q 'could not detect glTF format' "$report.err"; then
    jq -n --arg uri "$(basename "$model")" \
      --arg error "$(grep -m1 'could not detect glTF format' "$report.err")" \
      '{uri: $uri, fatalError: $error}' >"$report"
  else
    echo "validator failed on $model (exit $status):" >&2
    cat "$report.err" >&2
    rm -f "$report.out" "$report.err"
    exit 1
  fi
  rm -f "$report.out" "$report.err"
done
