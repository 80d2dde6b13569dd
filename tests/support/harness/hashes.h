// Hashes as the daemon computes them, from the bytes a test wrote.
#pragma once

#include <optional>
#include <string>
#include <vector>

namespace rdtf::itest {

std::string to_hex(const unsigned char* data, unsigned int size);

// SHA-256 of the given parts. length_prefixed: each part preceded by its size as a host-order
// 64-bit integer (the daemon's content_hash scheme); otherwise the plain SHA-256 of the bytes.
std::string sha256(const std::vector<std::string>& parts, bool length_prefixed);

// The plain SHA-256 of a byte string (what `sha256sum` prints).
std::string sha256_plain(const std::string& bytes);

// content_hash as the daemon computes it: the model file, then each file it refers to; a file
// not read (missing or refused: nullopt) counts as the length 2^64 - 1 and no bytes.
std::string content_hash(const std::string& model, const std::vector<std::optional<std::string>>& referenced = {});

inline std::string short_hash(const std::string& hash) { return hash.substr(0, 12); }

}  // namespace rdtf::itest
