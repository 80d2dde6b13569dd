// The one JSON form of a diagnostic: `rdtf inspect --json`, `rdtf validate --json`, the daemon's
// validation summaries and rdtf-echo's printing of an LCM diagnostic_t all use it.
//
//   {"severity": "error", "code": "URDF_INVALID", "file": "arm.urdf",
//    "pointer": "/robot/joint[@name='elbow']/limit/@effort", "line": 12, "message": "..."}
//
// "line" only when the diagnostic has one (URDF), "byteOffset" only when it has one (GLB).
#pragma once

#include <string>
#include <string_view>

#include "rdtf/diagnostics.h"
#include "rdtf/gltf.h"

namespace rdtf {

Json diagnostic_json(const Diagnostic& diagnostic);
Json diagnostics_json(const Diagnostics& diagnostics);

// Text that JSON can carry: file names are bytes on Linux and a parse error quotes the input as
// it is, so a byte that is not UTF-8 becomes U+FFFD instead of making the JSON writer throw.
std::string json_safe(std::string_view text);

}  // namespace rdtf
