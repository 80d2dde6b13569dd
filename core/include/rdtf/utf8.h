// UTF-8 as RFC 3629 defines it, for text that must become JSON (glTF names, diagnostics).
#pragma once

#include <cstddef>
#include <string_view>

namespace rdtf {

// Length of the well-formed UTF-8 sequence at text[i] (no overlong forms, no surrogates, nothing
// past U+10FFFF), or 0 if there is none. i < text.size().
std::size_t utf8_sequence_length(std::string_view text, std::size_t i);

}  // namespace rdtf
