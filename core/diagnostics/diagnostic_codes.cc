#include "rdtf/diagnostic_codes.h"

namespace rdtf {

const std::vector<DiagnosticCode>& diagnostic_codes() {
#define RDTF_DIAGNOSTIC_CODE_ROW(name, severities, area) DiagnosticCode{#name, severities, area},
  static const std::vector<DiagnosticCode> codes{RDTF_DIAGNOSTIC_CODES(RDTF_DIAGNOSTIC_CODE_ROW)};
#undef RDTF_DIAGNOSTIC_CODE_ROW
  return codes;
}

const DiagnosticCode* find_diagnostic_code(std::string_view code) {
  for (const DiagnosticCode& row : diagnostic_codes()) {
    if (row.code == code) return &row;
  }
  return nullptr;
}

}  // namespace rdtf
