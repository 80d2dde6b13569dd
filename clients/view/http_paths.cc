#include "http_paths.h"

#include <cctype>
#include <charconv>
#include <vector>

#include "rdtf/percent_decode.h"

namespace rdtf::view {
namespace {

std::vector<std::string_view> split(std::string_view text, char separator) {
  std::vector<std::string_view> parts;
  std::size_t start = 0;
  while (true) {
    const auto end = text.find(separator, start);
    parts.push_back(text.substr(start, end == std::string_view::npos ? std::string_view::npos : end - start));
    if (end == std::string_view::npos) return parts;
    start = end + 1;
  }
}

// A decoded path segment that may name a file: not empty, not "." or "..", no '/', '\' or control.
bool safe_segment(std::string_view segment) {
  if (segment.empty() || segment == "." || segment == "..") return false;
  for (const unsigned char c : segment) {
    if (c < 0x20 || c == 0x7f || c == '/' || c == '\\') return false;
  }
  return true;
}

Route not_found(std::string why) {
  Route r;
  r.why = std::move(why);
  return r;
}

// Decodes '/'-separated raw segments into a relative path of safe segments.
std::optional<std::string> safe_relative(const std::vector<std::string_view>& raw, std::size_t from) {
  std::string out;
  if (from >= raw.size()) return std::nullopt;
  for (std::size_t i = from; i < raw.size(); ++i) {
    const auto segment = percent_decode(raw[i]);
    if (!segment || !safe_segment(*segment)) return std::nullopt;
    out += (i == from ? "" : "/") + *segment;
  }
  return out;
}

bool starts_with(std::string_view text, std::string_view prefix) { return text.substr(0, prefix.size()) == prefix; }
bool ends_with(std::string_view text, std::string_view suffix) {
  return text.size() >= suffix.size() && text.substr(text.size() - suffix.size()) == suffix;
}

}  // namespace

std::string percent_encode(std::string_view text) {
  static const char* const kHex = "0123456789ABCDEF";
  std::string out;
  for (const unsigned char c : text) {
    if (std::isalnum(c) || c == '-' || c == '_' || c == '.' || c == '!' || c == '~' || c == '*' || c == '\'' ||
        c == '(' || c == ')') {
      out += static_cast<char>(c);
    } else {
      out += '%';
      out += kHex[c >> 4];
      out += kHex[c & 15];
    }
  }
  return out;
}

Route route(std::string_view target) {
  const auto query = target.find('?');
  if (query != std::string_view::npos) target = target.substr(0, query);
  if (target.empty() || target[0] != '/') return not_found("not an absolute path");
  if (target == "/") return Route{Route::Kind::kPage, "index.html", "", 0, ""};
  if (target == "/ws") return Route{Route::Kind::kSocket, "", "", 0, ""};
  const auto raw = split(target.substr(1), '/');
  if (raw[0] == "app" && raw.size() == 2) {
    const auto name = safe_relative(raw, 1);
    if (!name) return not_found("not a file name");
    for (const unsigned char c : *name) {
      if (!std::isalnum(c) && c != '-' && c != '_' && c != '.') return not_found("not a file name");
    }
    return Route{Route::Kind::kApp, *name, "", 0, ""};
  }
  if (raw[0] == "three") {
    const auto path = safe_relative(raw, 1);
    if (!path || !(starts_with(*path, "build/") || starts_with(*path, "examples/jsm/")) || !ends_with(*path, ".js")) {
      return not_found("not a module of three.js");
    }
    return Route{Route::Kind::kThree, *path, "", 0, ""};
  }
  if (raw[0] == "model" && raw.size() >= 4) {
    const auto id = percent_decode(raw[1]);
    if (!id || id->empty()) return not_found("malformed model id");
    std::int64_t revision = 0;
    const auto [end, error] = std::from_chars(raw[2].data(), raw[2].data() + raw[2].size(), revision);
    if (error != std::errc() || end != raw[2].data() + raw[2].size() || revision < 1) {
      return not_found("malformed revision");
    }
    const auto path = safe_relative(raw, 3);
    if (!path) return not_found("malformed file path");
    return Route{Route::Kind::kModelFile, *path, *id, revision, ""};
  }
  return not_found("no such page");
}

std::string model_file_url(const std::string& model_id, std::int64_t revision, const std::string& path) {
  std::string url = "/model/" + percent_encode(model_id) + "/" + std::to_string(revision);
  for (const auto segment : split(path, '/')) url += "/" + percent_encode(segment);
  return url;
}

std::string check_socket_origin(std::string_view host, std::string_view origin, bool loopback_only,
                                std::uint16_t port) {
  if (host.empty()) return "no Host header";
  if (origin != "http://" + std::string(host)) {
    return "Origin '" + std::string(origin.substr(0, 100)) + "' is not this viewer's page (http://" +
           std::string(host.substr(0, 100)) + ")";
  }
  if (!loopback_only) return "";
  const std::string suffix = ":" + std::to_string(port);
  if (!ends_with(host, suffix)) return "Host '" + std::string(host.substr(0, 100)) + "' does not name port " + std::to_string(port);
  const std::string_view name = host.substr(0, host.size() - suffix.size());
  if (name == "localhost" || name == "[::1]") return "";
  // 127.a.b.c with decimal parts.
  const auto parts = split(name, '.');
  bool ip4 = parts.size() == 4 && parts[0] == "127";
  for (const auto part : parts) {
    int value = -1;
    const auto [end, error] = std::from_chars(part.data(), part.data() + part.size(), value);
    ip4 = ip4 && !part.empty() && error == std::errc() && end == part.data() + part.size() && value >= 0 && value <= 255;
  }
  if (ip4) return "";
  return "Host '" + std::string(host.substr(0, 100)) + "' is not a loopback address (the viewer is bound to loopback)";
}

std::string content_type(std::string_view path) {
  if (ends_with(path, ".html")) return "text/html; charset=utf-8";
  if (ends_with(path, ".js") || ends_with(path, ".mjs")) return "text/javascript; charset=utf-8";
  if (ends_with(path, ".css")) return "text/css; charset=utf-8";
  if (ends_with(path, ".gltf")) return "model/gltf+json";
  if (ends_with(path, ".glb")) return "model/gltf-binary";
  if (ends_with(path, ".png")) return "image/png";
  if (ends_with(path, ".jpg") || ends_with(path, ".jpeg")) return "image/jpeg";
  if (ends_with(path, ".urdf")) return "application/xml";
  return "application/octet-stream";
}

std::string model_file_content_type(std::string_view path) {
  if (ends_with(path, ".gltf")) return "model/gltf+json";
  if (ends_with(path, ".glb")) return "model/gltf-binary";
  if (ends_with(path, ".png")) return "image/png";
  if (ends_with(path, ".jpg") || ends_with(path, ".jpeg")) return "image/jpeg";
  if (ends_with(path, ".webp")) return "image/webp";
  if (ends_with(path, ".ktx2")) return "image/ktx2";
  return "application/octet-stream";
}

}  // namespace rdtf::view
