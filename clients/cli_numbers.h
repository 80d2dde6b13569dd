// Number checks for the clients' CLI11 options that say what is wanted. CLI11's PositiveNumber and
// NonNegativeNumber (Debian's 2.3) answer "Value 0 not in range 0.000000 to 1797693...(309
// digits).000000", which names neither the rule nor the bound it broke.
#pragma once

#include <cmath>
#include <string>

#include <CLI/CLI.hpp>

namespace rdtf::cli_numbers {

inline CLI::Validator number_check(bool zero_allowed) {
  return CLI::Validator(
      [zero_allowed](std::string& text) -> std::string {
        double value = 0;
        if (!CLI::detail::lexical_cast(text, value)) return "'" + text + "' is not a number";
        if (!std::isfinite(value)) return "'" + text + "' is not a finite number (a double's range ends near 1.8e308)";
        if (value > 0 || (zero_allowed && value == 0)) return {};
        return "is " + text + "; it must be " + (zero_allowed ? "0 or more" : "more than 0");
      },
      zero_allowed ? "NUMBER >= 0" : "NUMBER > 0");
}

inline const CLI::Validator kPositive = number_check(false);
inline const CLI::Validator kNonNegative = number_check(true);

}  // namespace rdtf::cli_numbers
