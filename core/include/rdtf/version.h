// The version of rdtf and the git commit it was built from (written at build time by
// cmake/RdtfVersion.cmake; "unknown" when built outside a git checkout without a GIT_COMMIT file).
#pragma once

#include <string>

namespace rdtf {

const char* version();     // the project version, e.g. "0.1.0"
const char* git_commit();  // short commit hash, "-dirty" appended for uncommitted changes

// "<program> <version> (commit <hash>)": what `--version` prints.
inline std::string version_line(const std::string& program) {
  return program + " " + version() + " (commit " + git_commit() + ")";
}

}  // namespace rdtf
