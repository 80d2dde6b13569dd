// Writing a file so that readers see either the old content or the whole new one, never a part:
// write a temporary file in the same folder, fsync it, rename it over the target, fsync the folder.
#pragma once

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>

namespace rdtf {

// False, with `why`, when any step fails; the temporary file is then removed.
bool write_file_atomically(const std::filesystem::path& path, std::span<const std::uint8_t> bytes,
                           std::string& why);
bool write_file_atomically(const std::filesystem::path& path, std::string_view text,
                           std::string& why);

}  // namespace rdtf
