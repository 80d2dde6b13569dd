#include "support/harness/models.h"

#include <cstdint>
#include <cstdio>

#include "support/harness/files.h"
#include "support/harness/hashes.h"

namespace rdtf::itest {

std::string base64(const std::string& bytes) {
  static const char* const kTable = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  std::size_t i = 0;
  for (; i + 2 < bytes.size(); i += 3) {
    const unsigned v = (static_cast<unsigned char>(bytes[i]) << 16) |
                       (static_cast<unsigned char>(bytes[i + 1]) << 8) | static_cast<unsigned char>(bytes[i + 2]);
    out += kTable[v >> 18 & 63];
    out += kTable[v >> 12 & 63];
    out += kTable[v >> 6 & 63];
    out += kTable[v & 63];
  }
  if (i < bytes.size()) {
    unsigned v = static_cast<unsigned char>(bytes[i]) << 16;
    if (i + 1 < bytes.size()) v |= static_cast<unsigned char>(bytes[i + 1]) << 8;
    out += kTable[v >> 18 & 63];
    out += kTable[v >> 12 & 63];
    out += i + 1 < bytes.size() ? kTable[v >> 6 & 63] : '=';
    out += '=';
  }
  return out;
}

GeneratedModel box_model(const std::string& name, double half, int links, const std::string& bin_name) {
  // 8 corners (bit 0: +x, bit 1: +y, bit 2: +z), 12 triangles wound outwards.
  std::string bin;
  auto put_float = [&](float f) { bin.append(reinterpret_cast<const char*>(&f), 4); };
  auto put_u16 = [&](std::uint16_t v) { bin.append(reinterpret_cast<const char*>(&v), 2); };
  const float h = static_cast<float>(half);
  for (int c = 0; c < 8; ++c) {
    put_float(c & 1 ? h : -h);
    put_float(c & 2 ? h : -h);
    put_float(c & 4 ? h : -h);
  }
  const int quads[6][4] = {{1, 3, 7, 5}, {0, 4, 6, 2}, {2, 6, 7, 3}, {0, 1, 5, 4}, {4, 5, 7, 6}, {0, 2, 3, 1}};
  for (const auto& q : quads) {
    for (int v : {q[0], q[1], q[2], q[0], q[2], q[3]}) put_u16(static_cast<std::uint16_t>(v));
  }
  const std::size_t size = bin.size();  // 96 + 72 = 168 bytes.

  Json nodes = Json::array();
  if (links == 1) {
    nodes.push_back({{"name", name}, {"mesh", 0}});
  } else {
    // base (mesh) -> joint_1 -> link_1 -> [geom_1, joint_2 -> link_2 -> ...]
    nodes.push_back({{"name", name}, {"mesh", 0}, {"children", {1}}});
    for (int i = 1; i < links; ++i) {
      const int joint = static_cast<int>(nodes.size());
      const int link = joint + 1;
      const int geom = joint + 2;
      nodes.push_back({{"name", "joint_" + std::to_string(i)},
                       {"translation", {0.0, 2 * half + 0.01, 0.0}},
                       {"extras", {{"rdtf_joint", "revolute"}, {"rdtf_axis", {0.0, 0.0, 1.0}}}},
                       {"children", {link}}});
      Json link_node = {{"name", "link_" + std::to_string(i)}, {"children", {geom}}};
      if (i + 1 < links) link_node["children"].push_back(geom + 1);
      nodes.push_back(link_node);
      nodes.push_back({{"name", "geom_" + std::to_string(i)}, {"mesh", 0}});
    }
  }
  Json buffer = {{"byteLength", size}};
  buffer["uri"] = bin_name.empty() ? "data:application/octet-stream;base64," + base64(bin) : bin_name;
  const Json document = {
      {"asset", {{"version", "2.0"}, {"generator", "rdtf itest"}}},
      {"scene", 0},
      {"scenes", {{{"nodes", {0}}}}},
      {"nodes", nodes},
      {"meshes", {{{"primitives", {{{"attributes", {{"POSITION", 0}}}, {"indices", 1}}}}}}},
      {"accessors",
       {{{"bufferView", 0}, {"componentType", 5126}, {"count", 8}, {"type", "VEC3"},
         {"min", {-h, -h, -h}}, {"max", {h, h, h}}},
        {{"bufferView", 1}, {"componentType", 5123}, {"count", 36}, {"type", "SCALAR"}}}},
      {"bufferViews",
       {{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", 96}, {"target", 34962}},
        {{"buffer", 0}, {"byteOffset", 96}, {"byteLength", 72}, {"target", 34963}}}},
      {"buffers", {buffer}}};
  GeneratedModel model;
  model.gltf = document.dump(1);
  if (!bin_name.empty()) {
    model.bin = bin;
    model.bin_name = bin_name;
  }
  model.links = links;
  const double edge = 2.0 * static_cast<double>(h);
  model.link_mass = 1000.0 * edge * edge * edge;
  return model;
}

GeneratedModel many_parts_model(const std::string& name, int parts, double half) {
  GeneratedModel model = box_model(name, half);
  Json document = Json::parse(model.gltf);
  Json nodes = Json::array();
  Json root = {{"name", name}, {"children", Json::array()}};
  nodes.push_back(root);
  for (int i = 0; i < parts; ++i) {
    char part[32];
    std::snprintf(part, sizeof(part), "part_%05d", i);
    nodes[0]["children"].push_back(i + 1);
    nodes.push_back({{"name", part}, {"mesh", 0}, {"translation", {3.0 * half * i, 0.0, 0.0}}});
  }
  document["nodes"] = nodes;
  model.gltf = document.dump(1);
  model.link_mass *= parts;  // All in one link.
  return model;
}

fs::path write_model(const fs::path& folder, const std::string& file_name, const GeneratedModel& model) {
  if (!model.bin_name.empty()) write_in_place(folder / model.bin_name, model.bin);
  write_in_place(folder / file_name, model.gltf);
  return folder / file_name;
}

std::string content_hash(const GeneratedModel& model) {
  return model.bin_name.empty() ? content_hash(model.gltf) : content_hash(model.gltf, {model.bin});
}

std::string broken_model() {
  Json document = Json::parse(box_model("broken", 0.1).gltf);
  document["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = 7;
  return document.dump(1);
}

GeneratedModel gate_failing_model(const std::string& name, double half, const std::string& bin_name) {
  GeneratedModel model = box_model(name, half, 2, bin_name);
  Json document = Json::parse(model.gltf);
  document["nodes"][2]["extras"]["rdtf_mass"] = model.link_mass * 1e-6;
  model.gltf = document.dump(1);
  return model;
}

}  // namespace rdtf::itest
