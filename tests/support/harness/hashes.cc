#include "support/harness/hashes.h"

#include <openssl/evp.h>

#include <cstdint>

namespace rdtf::itest {

std::string to_hex(const unsigned char* data, unsigned int size) {
  static const char* const kHex = "0123456789abcdef";
  std::string out;
  for (unsigned int i = 0; i < size; ++i) {
    out += kHex[data[i] >> 4];
    out += kHex[data[i] & 15];
  }
  return out;
}

std::string sha256(const std::vector<std::string>& parts, bool length_prefixed) {
  EVP_MD_CTX* context = EVP_MD_CTX_new();
  EVP_DigestInit_ex(context, EVP_sha256(), nullptr);
  for (const auto& part : parts) {
    if (length_prefixed) {
      const std::uint64_t size = part.size();
      EVP_DigestUpdate(context, &size, sizeof(size));
    }
    EVP_DigestUpdate(context, part.data(), part.size());
  }
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int length = 0;
  EVP_DigestFinal_ex(context, digest, &length);
  EVP_MD_CTX_free(context);
  return to_hex(digest, length);
}

std::string sha256_plain(const std::string& bytes) { return sha256({bytes}, false); }

std::string content_hash(const std::string& model, const std::vector<std::optional<std::string>>& referenced) {
  EVP_MD_CTX* context = EVP_MD_CTX_new();
  EVP_DigestInit_ex(context, EVP_sha256(), nullptr);
  std::vector<std::optional<std::string>> parts{model};
  parts.insert(parts.end(), referenced.begin(), referenced.end());
  for (const auto& part : parts) {
    const std::uint64_t size = part ? part->size() : ~std::uint64_t{0};
    EVP_DigestUpdate(context, &size, sizeof(size));
    if (part) EVP_DigestUpdate(context, part->data(), part->size());
  }
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int length = 0;
  EVP_DigestFinal_ex(context, digest, &length);
  EVP_MD_CTX_free(context);
  return to_hex(digest, length);
}

}  // namespace rdtf::itest
