// The parts of HTTP rdtf-view checks itself: which file a request path names and whether a
// WebSocket upgrade comes from the viewer's own page. Pure functions, unit-tested.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "rdtf/percent_decode.h"

namespace rdtf::view {

// Request paths are decoded by rdtf::percent_decode (rdtf/percent_decode.h: nothing for a
// malformed escape or an encoded NUL).
using rdtf::percent_decode;
// encodeURIComponent's set: everything but A-Z a-z 0-9 - _ . ! ~ * ' ( ) as %XX.
std::string percent_encode(std::string_view text);

// What a GET asks for.
struct Route {
  enum class Kind { kPage, kApp, kThree, kModelFile, kSocket, kNotFound } kind = Kind::kNotFound;
  std::string path;      // kApp, kThree: the file below its folder; kModelFile: the manifest path
  std::string model_id;  // kModelFile
  std::int64_t revision = 0;  // kModelFile
  std::string why;       // kNotFound: the reason
};

// Routes:
//   /                                  the page (web/index.html)
//   /app/<file>                        web/<file>: one name of letters, digits, '-', '_', '.', no '..'
//   /three/<path>                      web/node_modules/three/<path>, below build/ or examples/jsm/
//   /model/<model id, percent-encoded as one segment>/<revision>/<manifest path>
//   /ws                                the WebSocket
// A query string is ignored. Paths with '..', '.', empty segments, backslashes or control
// characters are refused.
Route route(std::string_view target);

// The model file URL of a revision's file (the inverse of route()'s kModelFile).
std::string model_file_url(const std::string& model_id, std::int64_t revision, const std::string& path);

// Whether a WebSocket upgrade may command joints: its Origin must be this server's page
// ("http://" + Host), so that another web site the user visits cannot drive the robot through
// the user's browser. When the server is bound to loopback, Host must also name loopback
// (127.x.x.x, localhost, [::1]) with the server's port, which defeats DNS rebinding. Empty when
// allowed; else why not.
std::string check_socket_origin(std::string_view host, std::string_view origin, bool loopback_only,
                                std::uint16_t port);

// Content-Type by file name, for the page's own files.
std::string content_type(std::string_view path);

// Content-Type of a model's file: whoever can write into rdtfd's folder names them, so a name
// never makes one active content (a buffer called payload.html served as text/html would run as
// this page's origin and command joints): glTF and the image types glTF allows, else
// application/octet-stream.
std::string model_file_content_type(std::string_view path);

}  // namespace rdtf::view
