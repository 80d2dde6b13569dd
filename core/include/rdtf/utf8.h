// UTF-8 as RFC 3629 defines it, for text that must become JSON (glTF names, diagnostics).
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

namespace rdtf {

// Length of the well-formed UTF-8 sequence at text[i] (no overlong forms, no surrogates, nothing
// past U+10FFFF), or 0 if there is none. i < text.size().
std::size_t utf8_sequence_length(std::string_view text, std::size_t i);

// Whether all of `text` is well-formed UTF-8 (as utf8_sequence_length judges each sequence).
bool is_utf8(std::string_view text);

// One line of text as a terminal or a log shows it safely: a backslash, a control character
// (newline, carriage return, tab, escape, NUL, DEL) and a byte that is not UTF-8 are escaped
// ("\\", "\n", "\x1b", "\xff"), and so are the C1 controls, the bidirectional formatting
// characters and U+2028/U+2029 ("\u0085", "\u202e"), so a node name or a file name cannot start
// a line of its own, move the cursor, recolour a terminal or reorder what follows it on the line.
// Other well-formed UTF-8 is kept.
std::string escape_for_terminal(std::string_view text);

}  // namespace rdtf
