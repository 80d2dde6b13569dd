#include "rdtf/json_text.h"

#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

namespace rdtf {
namespace {

// Below this many keys an object is searched as ordered_map searches it, by walking it: most
// glTF objects have a handful of keys, and a walk of them is cheaper than hashing.
constexpr std::size_t kIndexFrom = 16;

// nlohmann's json_sax_dom_parser, but for the one step that is quadratic in ordered_json: finding
// whether a key was seen before in the object being read.
class OrderedDomBuilder {
 public:
  explicit OrderedDomBuilder(Json& root) : root_(root) {}

  bool null() { return put(Json(nullptr)) != nullptr; }
  bool boolean(bool value) { return put(Json(value)) != nullptr; }
  bool number_integer(Json::number_integer_t value) { return put(Json(value)) != nullptr; }
  bool number_unsigned(Json::number_unsigned_t value) { return put(Json(value)) != nullptr; }
  bool number_float(Json::number_float_t value, const Json::string_t& /*text*/) {
    return put(Json(value)) != nullptr;
  }
  bool string(Json::string_t& value) { return put(Json(std::move(value))) != nullptr; }
  bool binary(Json::binary_t& value) { return put(Json(std::move(value))) != nullptr; }

  bool start_object(std::size_t /*elements: unknown in text*/) {
    open_.push_back({put(Json(Json::value_t::object)), {}});
    return true;
  }
  bool start_array(std::size_t /*elements*/) {
    open_.push_back({put(Json(Json::value_t::array)), {}});
    return true;
  }
  bool end_object() {
    open_.pop_back();
    return true;
  }
  bool end_array() {
    open_.pop_back();
    return true;
  }

  // As ordered_map's operator[]: a new key goes last with a null value; a key seen before in
  // this object keeps its place and gets the value that follows (the last one wins).
  bool key(Json::string_t& key) {
    Open& open = open_.back();
    auto& entries = static_cast<Json::object_t::Container&>(open.value->get_ref<Json::object_t&>());
    if (entries.size() < kIndexFrom) {
      for (auto& entry : entries) {
        if (entry.first == key) {
          element_ = &entry.second;
          return true;
        }
      }
    } else {
      if (open.index.empty()) {
        open.index.reserve(2 * kIndexFrom);
        for (std::size_t i = 0; i < entries.size(); ++i) open.index.emplace(entries[i].first, i);
      }
      const auto [at, added] = open.index.emplace(key, entries.size());
      if (!added) {
        element_ = &entries[at->second].second;
        return true;
      }
    }
    entries.emplace_back(std::move(key), nullptr);
    element_ = &entries.back().second;
    return true;
  }

  template <class Exception>
  bool parse_error(std::size_t /*byte*/, const std::string& /*token*/, const Exception& error) {
    throw error;  // Json::parse's own exception, with its byte (Json::parse_error) or code.
  }

 private:
  struct Open {
    Json* value;
    // Key -> place in the object, built once it has kIndexFrom keys, dropped when it closes.
    std::unordered_map<std::string, std::size_t> index;
  };

  // Where a value goes: the root, the end of the open array, or the open object's last key.
  // Pointers into a parent stay valid while a child is open: only the innermost container grows.
  Json* put(Json&& value) {
    if (open_.empty()) {
      root_ = std::move(value);
      return &root_;
    }
    Json& parent = *open_.back().value;
    if (parent.is_array()) {
      auto& items = parent.get_ref<Json::array_t&>();
      items.push_back(std::move(value));
      return &items.back();
    }
    *element_ = std::move(value);
    return element_;
  }

  Json& root_;
  std::vector<Open> open_;
  Json* element_ = nullptr;
};

}  // namespace

Json parse_json_text(std::string_view text) {
  Json root;
  OrderedDomBuilder builder(root);
  Json::sax_parse(text.begin(), text.end(), &builder);
  return root;
}

}  // namespace rdtf
