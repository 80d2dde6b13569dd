#include "rdtf/link_inertia.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <deque>
#include <future>
#include <map>
#include <numeric>
#include <system_error>
#include <thread>

#include "rdtf/completion.h"
#include "rdtf/geometry.h"
#include "rdtf/instancing.h"
#include "rdtf/mesh_checks.h"
#include "skinning.h"
#include "winding_sample.h"
#include "rdtf/diagnostic_codes.h"

namespace rdtf {
namespace {

// From this many triangles a mesh's surface check runs on a thread of its own while the calling
// thread integrates the mesh's mass properties: the two only read the mesh. Below it the thread
// costs more than it saves (starting one takes about 0.1 ms; the check takes about 30 ns a
// triangle, the mass kernel about 6).
constexpr std::uint64_t kSurfaceCheckThreadTriangles = 100000;

struct MeshGeometry {
  // One per triangle primitive, read in place from the buffers where possible (issue 6), with
  // views of them (into the buffers or the primitives' copies; those move with the vectors).
  std::vector<PrimitiveTriangles> primitives;
  std::vector<TriangleMeshView> pieces;
  std::vector<std::size_t> primitive_index;

  // Starts the surface check of `pieces`: on a thread of its own for a large mesh on a machine with
  // more than one processor (the result is the same either way), else here and now.
  void check_surface() {
    std::uint64_t triangles = 0;
    for (const TriangleMeshView& piece : pieces) triangles += piece.triangle_count;
    if (triangles >= kSurfaceCheckThreadTriangles && std::thread::hardware_concurrency() > 1) {
      try {
        // The check shares its work with one more thread: on a machine of two processors the
        // mass kernel on this one is done long before it (about 6 ns a triangle against 30).
        pending_ = std::async(std::launch::async, [views = std::span<const TriangleMeshView>(pieces)] {
          return analyze_surface(views, 2);
        });
        return;
      } catch (const std::system_error&) {
        // No thread to be had (a process or memory limit): the check runs here instead.
      }
    }
    topology_ = analyze_surface(std::span<const TriangleMeshView>(pieces));
  }
  // The surface check's result, waited for if it is still running (its exception, if any, is
  // thrown here, as it would have been by a check run in place).
  const SurfaceTopology& topology() const {
    if (pending_.valid()) topology_ = pending_.get();
    return topology_;
  }
  // The primitives as TriangleMesh values, made only for the skinned path, which needs them.
  const std::vector<TriangleMesh>& meshes() const {
    if (meshes_.size() != primitives.size()) {
      meshes_.clear();
      for (const PrimitiveTriangles& primitive : primitives) meshes_.push_back(primitive.mesh());
    }
    return meshes_;
  }

 private:
  mutable std::vector<TriangleMesh> meshes_;
  mutable SurfaceTopology topology_;
  // Declared after `pieces`, so destroyed before them: a future of std::async waits for its
  // thread when destroyed, so a check still running never outlives the views it reads.
  mutable std::future<SurfaceTopology> pending_;
};

// Counted twice or subtracted, from this fraction of a link's volume on, is reported: the
// winding sample's grid error is far below it (docs/diagnostics.md, LINK_PARTS_OVERLAP), and a
// smaller share moves the mass less than a modeller's own rounding of a density does.
constexpr double kReportedVolumeFraction = 0.005;

// A closed mesh whose volume is below this fraction of the cube on its extent encloses nothing:
// rounding of faces that cancel (a double-sided export) leaves about 1e-16 of it, and a sheet
// 1 mm thick across 1 m is 1e-3 / 1.7^3, far above.
constexpr double kNoVolume = 1e-9;

// One closed, consistently wound solid of a link, kept to look for overlaps once the link has
// all of them: a mesh node's mesh, or one of its EXT_mesh_gpu_instancing instances.
struct LinkSolid {
  std::span<const TriangleMeshView> pieces;  // into the geometry cache, or a bone's kept pieces
  Eigen::Affine3d X_LM = Eigen::Affine3d::Identity();
  int orientation = 1;   // -1: the mesh winds clockwise as a whole (MESH_INSIDE_OUT)
  std::size_t node = 0;  // as reported: the input's node
  int instance = -1;     // -1: not instanced
};

// A mesh as drawn with morph weights (none: as stored); every node drawing it so shares one.
using GeometryKey = std::pair<std::size_t, std::vector<double>>;

const MeshGeometry& geometry_of(const GltfAsset& asset, std::size_t mesh, std::vector<double> weights,
                                std::map<GeometryKey, MeshGeometry>& cache, Diagnostics& diag) {
  GeometryKey key{mesh, std::move(weights)};
  const auto found = cache.find(key);
  if (found != cache.end()) return found->second;
  MeshGeometry geometry;
  const Json& primitives = asset.document["meshes"][mesh]["primitives"];
  for (std::size_t p = 0; p < primitives.size(); ++p) {
    auto triangles = read_primitive_in_place(asset, mesh, p, diag, key.second);
    if (!triangles) continue;
    geometry.primitives.push_back(std::move(*triangles));
    geometry.primitive_index.push_back(p);
  }
  for (const PrimitiveTriangles& primitive : geometry.primitives) {
    geometry.pieces.push_back(primitive.view());
  }
  // Started once the geometry has its place in the cache: the check reads the views where they
  // stay until the cache goes.
  MeshGeometry& cached = cache.emplace(std::move(key), std::move(geometry)).first->second;
  cached.check_surface();
  return cached;
}

std::optional<double> positive_extra(const Json& document, std::size_t node, const char* key,
                                     Diagnostics& diag) {
  const Json& n = document["nodes"][node];
  if (!n.contains("extras") || !n["extras"].is_object() || !n["extras"].contains(key)) {
    return std::nullopt;
  }
  const Json& value = n["extras"][key];
  if (!value.is_number() || !std::isfinite(value.get<double>()) || value.get<double>() <= 0) {
    diag.error(codes::RDTF_INVALID_VALUE, json_pointer("/nodes", node) + "/extras/" + key,
               node_label(document, node) + ": " + key + " is " + value_text(value) +
                   ", not a positive number" + text_value_advice(value, key));
    return std::nullopt;
  }
  return value.get<double>();
}

// rdtf_density on the node or an ancestor, up to and including `link_node`.
double density_for(const Json& document, const std::vector<int>& parents, int node,
                   int link_node, double default_density, Diagnostics& diag) {
  for (int up = node; up >= 0; up = parents[up]) {
    if (auto density = positive_extra(document, up, "rdtf_density", diag)) return *density;
    if (up == link_node) break;
    // Past the joint node that carries the link (owning_link_nodes): the link's own, then no more.
    if (parents[up] >= 0 && link_node >= 0 && parents[up] == parents[link_node]) {
      if (auto density = positive_extra(document, link_node, "rdtf_density", diag)) return *density;
      break;
    }
  }
  return default_density;
}

// Where a mesh's link has an authored inertial (`authored_by`, the link's name; "" where its mass
// comes from its meshes), what makes the mesh's volume unreliable changes no mass: it is said as
// information, with why, and not as a warning about a mass (every open visual of a published
// robot, whose masses are its <inertial>s, was "its mass is unreliable").
void report_shape(Diagnostics& diag, const char* code, const std::string& pointer, const std::string& finding,
                  const std::string& consequence, const std::string& authored_by) {
  if (authored_by.empty()) {
    diag.warning(code, pointer, finding + consequence);
  } else {
    diag.info(code, pointer,
              finding + "; link '" + authored_by +
                  "' has an authored inertial, so no mass comes from this mesh (only its own volume and density, "
                  "as rdtf inspect lists them, are affected)");
  }
}

// Reports what the surface check found.
void report_topology(const MeshGeometry& geometry, const std::string& pointer,
                     const std::string& name, Diagnostics& diag, const std::string& authored_by) {
  const SurfaceTopology& t = geometry.topology();
  if (!t.closed()) {
    report_shape(diag, codes::MESH_OPEN, pointer,
                 "mesh of '" + name + "' is not closed (" + std::to_string(t.boundary_edges) +
                     " boundary edges, " + std::to_string(t.nonmanifold_edges) + " non-manifold edges)",
                 ": its volume, and so its mass, is unreliable", authored_by);
  }
  if (!t.consistently_oriented()) {
    report_shape(diag, codes::MESH_INCONSISTENT_WINDING, pointer,
                 "mesh of '" + name + "' has " + std::to_string(t.misoriented_edges) +
                     " edges whose triangles wind the same way: some faces are flipped",
                 ", so its mass is wrong; recalculate normals outside in the modeller", authored_by);
  }
}

// A solid's integrals, inside-out ones turned right with a warning.
VolumeIntegrals oriented(VolumeIntegrals integrals, const std::string& pointer, const std::string& name,
                         Diagnostics& diag, const std::string& authored_by, int instance = -1) {
  if (integrals.volume < 0) {
    report_shape(diag, codes::MESH_INSIDE_OUT, pointer,
                 "mesh of '" + name + "'" + (instance >= 0 ? " (instance " + std::to_string(instance) + ")" : "") +
                     " is inside out (signed volume " + format_number(integrals.volume, 3) +
                     " m^3): its faces wind clockwise",
                 "; mass computed as if turned right", authored_by);
    integrals.volume = -integrals.volume;
    integrals.second_central = -integrals.second_central;
  }
  return integrals;
}

// `inertial` (at `where`, about the node `label`): an extras.RDTF inertial object or the node
// extras rdtf_inertial that carries the same keys.
std::optional<MassProperties> authored_inertial(const Json& inertial, const std::string& where,
                                                const std::string& label, Diagnostics& diag) {
  if (!inertial.is_object()) {
    diag.error(codes::RDTF_INVALID_VALUE, where,
               label + ": an inertial is an object (mass, gravityCenter, inertia); this one is " + value_text(inertial));
    return std::nullopt;
  }
  if (inertial.contains("source") && inertial["source"] == "computed") return std::nullopt;
  auto number = [&](const Json& value) { return value.is_number() && std::isfinite(value.get<double>()); };
  MassProperties result;
  if (!inertial.contains("mass") || !number(inertial["mass"])) {
    diag.error(codes::RDTF_INVALID_VALUE, where + "/mass",
               label + ": an authored inertial needs a finite mass; it has " +
                   (inertial.contains("mass") ? value_text(inertial["mass"]) : std::string("none")));
    return std::nullopt;
  }
  result.mass = inertial["mass"].get<double>();
  if (result.mass < 0) {
    diag.error(codes::RDTF_INVALID_VALUE, where + "/mass",
               label + ": mass " + value_text(inertial["mass"]) + " kg is negative: a mass is 0 or more");
    return std::nullopt;
  }
  // rdtf writes "link" (the link's frame, docs/format.md) and reads no other: a tensor said to be
  // in another frame ("world") would be read in the wrong one.
  if (inertial.contains("frame") && inertial["frame"] != "link") {
    diag.error(codes::RDTF_INVALID_VALUE, where + "/frame",
               label + ": frame " + value_text(inertial["frame"]) +
                   " is not \"link\", the only frame an inertial is given in (the link's)");
    return std::nullopt;
  }
  if (inertial.contains("gravityCenter")) {
    const Json& c = inertial["gravityCenter"];
    if (!c.is_array() || c.size() != 3 || !number(c[0]) || !number(c[1]) || !number(c[2])) {
      diag.error(codes::RDTF_INVALID_VALUE, where + "/gravityCenter",
                 label + ": gravityCenter is " + value_text(c) + ", not 3 finite numbers");
      return std::nullopt;
    }
    result.center_of_mass = {c[0].get<double>(), c[1].get<double>(), c[2].get<double>()};
  }
  if (inertial.contains("inertia")) {
    const Json& I = inertial["inertia"];
    const bool six = I.is_array() && I.size() == 6;
    const bool nine = I.is_array() && I.size() == 9;
    bool valid = six || nine;
    for (std::size_t i = 0; valid && i < I.size(); ++i) valid = number(I[i]);
    if (!valid) {
      diag.error(codes::RDTF_INVALID_VALUE, where + "/inertia",
                 label + ": inertia is " + value_text(I) +
                     "; it must be six numbers [ixx, ixy, ixz, iyy, iyz, izz] or nine, a row-major 3x3 matrix");
      return std::nullopt;
    }
    if (six) {
      const double ixx = I[0].get<double>(), ixy = I[1].get<double>(), ixz = I[2].get<double>();
      const double iyy = I[3].get<double>(), iyz = I[4].get<double>(), izz = I[5].get<double>();
      result.inertia << ixx, ixy, ixz, ixy, iyy, iyz, ixz, iyz, izz;
    } else {
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) result.inertia(r, c) = I[r * 3 + c].get<double>();
      // An inertia tensor is symmetric: nine numbers that are not say two tensors, and what read the
      // upper triangle (inspect, the URDF) and what kept all nine (the RDTF) disagreed (s90urdf D8).
      // Within the dynamics check's symmetry tolerance (1e-9 of the largest entry: a CAD tool that
      // prints ten digits, each entry computed on its own), the two halves are averaged.
      const double scale = result.inertia.cwiseAbs().maxCoeff();
      for (int r = 0; r < 3; ++r) {
        for (int c = r + 1; c < 3; ++c) {
          if (std::abs(result.inertia(r, c) - result.inertia(c, r)) <= 1e-9 * scale) continue;
          diag.error(codes::RDTF_INVALID_VALUE, where + "/inertia",
                     label + ": inertia " + value_text(I) + " is not symmetric: row " + std::to_string(r + 1) +
                         ", column " + std::to_string(c + 1) + " is " + value_text(Json(result.inertia(r, c))) +
                         " but row " + std::to_string(c + 1) + ", column " + std::to_string(r + 1) + " is " +
                         value_text(Json(result.inertia(c, r))));
          return std::nullopt;
        }
      }
      result.inertia = 0.5 * (result.inertia + result.inertia.transpose()).eval();
    }
  }
  if (inertial.contains("volume") && number(inertial["volume"])) result.volume = inertial["volume"].get<double>();
  return result;
}

std::string mass_text(const std::optional<MassProperties>& inertial) {
  return inertial ? "mass " + value_text(Json(inertial->mass)) + " kg" : std::string("computed from the geometry");
}

// The inertial node's rdtf_inertial against the extras.RDTF inertial that took precedence (`entry`,
// nullopt when computed). A tool that keeps node extras only (Blender's importer) would read the
// node extra instead, so a difference is a warning, and the writer rewrites the node extra.
bool warn_if_extras_differ(const Json& node, const std::optional<MassProperties>& entry, const std::string& label,
                           int inertial_node, Diagnostics& diag) {
  if (!node.contains("extras") || !node["extras"].is_object() || !node["extras"].contains("rdtf_inertial")) return false;
  const std::string pointer = json_pointer("/nodes", inertial_node) + "/extras/rdtf_inertial";
  Diagnostics scratch;
  const auto extras = authored_inertial(node["extras"]["rdtf_inertial"], pointer, label, scratch);
  std::string difference;
  if (const Diagnostic* error = scratch.first_error()) {
    difference = "it is invalid (" + error->message + ")";
  } else if (extras.has_value() != entry.has_value()) {
    difference = "it says " + mass_text(extras) + ", extras.RDTF says " + mass_text(entry);
  } else if (extras) {
    const auto agree = [](double a, double b, double scale) { return std::abs(a - b) <= 1e-9 * std::max(1e-300, scale); };
    const double length = std::max({1.0, extras->center_of_mass.norm(), entry->center_of_mass.norm()});
    const double moment = std::max(extras->inertia.cwiseAbs().maxCoeff(), entry->inertia.cwiseAbs().maxCoeff());
    if (!agree(extras->mass, entry->mass, std::max(std::abs(extras->mass), std::abs(entry->mass)))) {
      difference = "it says " + mass_text(extras) + ", extras.RDTF says " + mass_text(entry);
    } else if (!agree((extras->center_of_mass - entry->center_of_mass).norm(), 0, length)) {
      difference = "its gravityCenter differs from extras.RDTF's by " +
                   value_text(Json((extras->center_of_mass - entry->center_of_mass).norm())) + " m";
    } else if (!agree((extras->inertia - entry->inertia).cwiseAbs().maxCoeff(), 0, moment)) {
      difference = "its inertia differs from extras.RDTF's by up to " +
                   value_text(Json((extras->inertia - entry->inertia).cwiseAbs().maxCoeff())) + " kg m^2";
    }
  }
  if (difference.empty()) return false;
  diag.warning(codes::RDTF_NODE_EXTRAS_IGNORED, pointer,
               label + ": rdtf_inertial: " + difference +
                   "; extras.RDTF takes precedence, and the output's rdtf_inertial is rewritten to agree");
  return true;
}

std::string solid_label(const Json& document, const LinkSolid& solid) {
  std::string label = node_label(document, solid.node);
  if (solid.instance >= 0) label += " (instance " + std::to_string(solid.instance) + ")";
  return label;
}

// The links of each rigid body: joined by fixed joints (union-find), in link order.
std::vector<std::vector<std::size_t>> rigid_bodies(const Robot& robot) {
  std::vector<std::size_t> up(robot.links.size());
  std::iota(up.begin(), up.end(), std::size_t{0});
  const auto find = [&](std::size_t l) {
    while (up[l] != l) l = up[l] = up[up[l]];
    return l;
  };
  for (const Joint& joint : robot.joints) {
    if (joint.kind != JointKind::kFixed || joint.parent_link < 0 || joint.child_link < 0) continue;
    const std::size_t a = find(static_cast<std::size_t>(joint.parent_link));
    const std::size_t b = find(static_cast<std::size_t>(joint.child_link));
    up[std::max(a, b)] = std::min(a, b);
  }
  std::map<std::size_t, std::vector<std::size_t>> bodies;
  for (std::size_t l = 0; l < robot.links.size(); ++l) bodies[find(l)].push_back(l);
  std::vector<std::vector<std::size_t>> result;
  for (auto& [root, links] : bodies) result.push_back(std::move(links));
  return result;
}

}  // namespace

struct LinkSolids::State {
  // Declared first, so destroyed last: the solids point into them. Deques: an element stays where
  // it is as more are added.
  std::map<GeometryKey, MeshGeometry> cache;
  std::deque<std::vector<TriangleMesh>> bone_meshes;      // skinned parts, in their bind pose
  std::deque<std::vector<TriangleMeshView>> bone_views;  // views of them
  std::vector<std::vector<LinkSolid>> by_link;
};

LinkSolids::LinkSolids() : state_(std::make_unique<State>()) {}
LinkSolids::~LinkSolids() = default;
LinkSolids::LinkSolids(LinkSolids&&) noexcept = default;
LinkSolids& LinkSolids::operator=(LinkSolids&&) noexcept = default;

void compute_link_inertia(const GltfAsset& asset, const std::vector<NodeType>& types,
                          double default_density, Robot& robot, Diagnostics& diag,
                          const std::vector<int>& carried_by, LinkSolids* solids_out) {
  const Json& document = asset.document;
  if (!document.contains("nodes")) return;
  const auto parents = node_parents(document);
  const auto world = node_world_transforms(document);
  std::vector<int> link_of_node(types.size(), -1);
  for (std::size_t l = 0; l < robot.links.size(); ++l) link_of_node[robot.links[l].node] = static_cast<int>(l);
  const std::vector<int> owners = owning_link_nodes(document, types);

  std::vector<std::vector<MassPiece>> pieces(robot.links.size());
  std::vector<bool> flattened(robot.links.size(), false);  // a mesh of it is scaled to nothing
  // Mesh nodes whose own rdtf_mass set their density, by link: a link's rdtf_mass rescales them.
  std::vector<std::vector<std::pair<std::size_t, double>>> mesh_masses(robot.links.size());
  LinkSolids own_solids;
  LinkSolids::State& kept = (solids_out != nullptr ? *solids_out : own_solids).state();
  std::map<GeometryKey, MeshGeometry>& cache = kept.cache;
  std::vector<std::vector<LinkSolid>>& link_solids = kept.by_link;
  link_solids.assign(robot.links.size(), {});
  std::vector<std::string> entry_pointers;
  const auto entries = rdtf_entries(document, entry_pointers);
  // The name of each link whose mass is an authored inertial (extras.RDTF's, or an inertial node's
  // rdtf_inertial), "" for the others: its meshes give it no mass (report_shape).
  std::vector<std::string> authored_by(robot.links.size());
  for (std::size_t l = 0; l < robot.links.size(); ++l) {
    for (const Json& child : document["nodes"][robot.links[l].node].value("children", Json::array())) {
      const auto c = child.get<std::size_t>();
      if (c >= types.size() || types[c] != NodeType::kInertial) continue;
      const Json& node = document["nodes"][c];
      if ((entries[c] != nullptr && entries[c]->contains("inertial")) ||
          (node.contains("extras") && node["extras"].is_object() && node["extras"].contains("rdtf_inertial"))) {
        authored_by[l] = robot.links[l].name;
      }
    }
  }

  for (std::size_t node = 0; node < types.size(); ++node) {
    // A mesh on a node typed otherwise by its author (a link typed "joint" in extras.RDTF): its
    // mass would vanish without a word.
    if (types[node] != NodeType::kMesh && types[node] != NodeType::kLink && types[node] != NodeType::kNone &&
        document["nodes"][node].contains("mesh")) {
      diag.warning(codes::MESH_WITHOUT_LINK, json_pointer("/nodes", node),
                   node_label(document, node) + " has a mesh but is typed " + to_string(types[node]) +
                       " (extras.RDTF or rdtf_type): its mesh adds no mass to any link; type it link or mesh");
      continue;
    }
    if (types[node] != NodeType::kMesh || !document["nodes"][node].contains("mesh")) continue;
    const int owner = owners[node];
    // Named as the input names it: a mesh split off its link node by its link node.
    const std::size_t reported = node < carried_by.size() && carried_by[node] >= 0 ? static_cast<std::size_t>(carried_by[node]) : node;
    const std::string pointer = json_pointer("/nodes", reported);
    const std::string name = node_name(document, reported);
    const bool skinned = document["nodes"][node].contains("skin");
    if (owner < 0 && !skinned) {
      diag.warning(codes::MESH_WITHOUT_LINK, pointer, "mesh node '" + name + "' belongs to no link; ignored");
      continue;
    }
    const auto mesh = document["nodes"][node]["mesh"].get<std::size_t>();
    const MeshGeometry& geometry = geometry_of(asset, mesh, morph_weights(document, node), cache, diag);
    if (geometry.pieces.empty()) continue;
    if (skinned) report_topology(geometry, pointer, name, diag, "");
    // What is found from here on is reported after the surface check's findings, as when the
    // check ran before it: the check of a large mesh may still be running (check_surface).
    Diagnostics after_check(diag.file());
    const double density =
        density_for(document, parents, static_cast<int>(node), owner, default_density, after_check);
    const auto mass_override = positive_extra(document, node, "rdtf_mass", after_check);

    if (skinned) {
      // A skinned mesh is placed by its bones, not by its node (glTF 2.0 3.7.3.3), and
      // EXT_mesh_gpu_instancing places instances relative to the node: where instances of a
      // skinned mesh go is undefined, and counting one of them would weigh the others as nothing.
      const Json& node_json = document["nodes"][node];
      if (node_json.contains("extensions") && node_json["extensions"].is_object() &&
          node_json["extensions"].contains("EXT_mesh_gpu_instancing")) {
        diag.error(codes::INSTANCING_INVALID, pointer + "/extensions/EXT_mesh_gpu_instancing",
                   "mesh node '" + name + "' is skinned and instanced: its bones place a skinned mesh, and "
                   "where instances of it go is undefined; instance the bones' parts as plain meshes, or "
                   "remove the instancing");
        continue;
      }
      diag.append(after_check);
      // Skinned: each bone gets the parts of the mesh bound to it, posed by its skinning matrix.
      const SurfaceTopology& topology = geometry.topology();
      struct BonePart {
        int link;
        Eigen::Affine3d X_LV;
        VolumeIntegrals signed_integrals, integrals;
        std::vector<TriangleMesh> pieces;
      };
      std::vector<BonePart> parts;
      double volume = 0;
      for (BoneGeometry& bone : split_by_bone(asset, node, geometry.meshes(), geometry.primitive_index, world, diag)) {
        const int link = link_of_node[bone.joint_node];
        if (link < 0) {  // A bone outside the scene: typing gives it no type, and the robot no link.
          diag.warning(codes::MESH_WITHOUT_LINK, pointer,
                       "the part of skinned mesh node '" + name + "' bound to " + node_label(document, bone.joint_node) +
                           " belongs to no link: that bone is outside the scene; ignored");
          continue;
        }
        BonePart& part = parts.emplace_back();
        part.link = link;
        part.X_LV = robot.links[link].X_SL.inverse() * world[bone.joint_node] * bone.inverse_bind;
        part.signed_integrals = integrate_solid(bone.pieces, part.X_LV);
        part.integrals = oriented(part.signed_integrals, pointer, name, diag, authored_by[static_cast<std::size_t>(link)]);
        part.pieces = std::move(bone.pieces);
        volume += part.integrals.volume;
      }
      // The node's rdtf_mass is the whole mesh's, shared by its bones as their volumes are (it was
      // ignored here, the default density weighing the mesh instead: s100xform D3).
      const double mesh_density = mass_override && volume > 0 ? *mass_override / volume : density;
      for (BonePart& part : parts) {
        pieces[part.link].push_back({part.integrals, mesh_density});
        robot.links[part.link].meshes.push_back({static_cast<int>(node), part.integrals.volume, mesh_density});
        if (mass_override && volume > 0) {
          mesh_masses[part.link].emplace_back(reported, mesh_density * part.integrals.volume);
        }
        if (!topology.closed() || !topology.consistently_oriented()) continue;
        // The bone's part, kept for the overlap check (parts of one bone can overlap as any
        // link's can).
        std::vector<TriangleMeshView>& views = kept.bone_views.emplace_back();
        const std::vector<TriangleMesh>& meshes = kept.bone_meshes.emplace_back(std::move(part.pieces));
        for (const TriangleMesh& piece : meshes) views.push_back(TriangleMeshView::of(piece));
        link_solids[part.link].push_back({views, part.X_LV, part.signed_integrals.volume < 0 ? -1 : 1, reported, -1});
      }
      continue;
    }
    const int link = link_of_node[owner];
    if (link < 0) {  // Typing keeps links in the scene, which the robot holds; stay safe regardless.
      diag.warning(codes::MESH_WITHOUT_LINK, pointer, "mesh node '" + name + "' belongs to no link of the robot; ignored");
      continue;
    }
    const Eigen::Affine3d X_LN = robot.links[link].X_SL.inverse() * world[node];
    // A scale of 0 on the node or an ancestor flattens the mesh: its volume, and with it a part of
    // the link's mass, vanish. (A matrix that does so is refused as not decomposable; a TRS scale
    // of 0 is valid glTF, and cut a link's mass without a word.)
    if (X_LN.linear().determinant() == 0.0) {
      flattened[static_cast<std::size_t>(link)] = true;
      after_check.warning(codes::MESH_SCALED_TO_NOTHING, pointer,
                          "mesh node '" + name + "' is scaled to nothing (a scale of 0 on it or an ancestor): "
                          "it adds no volume and no mass to its link; give it a non-zero scale, or remove it");
    }
    // Every instance (EXT_mesh_gpu_instancing) is a solid of the link; a node's rdtf_mass is
    // the mass of them all.
    std::uint64_t triangles = 0;
    for (const TriangleMeshView& piece : geometry.pieces) triangles += piece.triangle_count;
    const auto instances =
        instance_transforms(asset, node, asset.limits.max_triangles / std::max<std::uint64_t>(triangles, 1),
                            after_check, reported);
    // The mass kernel runs while the surface check of a large mesh does (check_surface).
    std::vector<VolumeIntegrals> solids;
    if (instances) {
      for (std::size_t k = 0; k < instances->size(); ++k) {
        const Eigen::Affine3d X_LI = X_LN * (*instances)[k];
        // An instance's own SCALE of 0 flattens it as a node's does (above).
        if (X_LN.linear().determinant() != 0.0 && X_LI.linear().determinant() == 0.0) {
          after_check.warning(codes::MESH_SCALED_TO_NOTHING, pointer + "/extensions/EXT_mesh_gpu_instancing",
                              "instance " + std::to_string(k) + " of mesh node '" + name +
                                  "' is scaled to nothing (a SCALE of 0 on some axis): it adds no volume and no "
                                  "mass to its link; give it a non-zero scale, or remove it");
        }
        solids.push_back(integrate_solid(std::span<const TriangleMeshView>(geometry.pieces), X_LI));
      }
    }
    report_topology(geometry, pointer, name, diag, authored_by[static_cast<std::size_t>(link)]);
    diag.append(after_check);
    if (!instances) continue;
    double volume = 0;
    // A closed, consistently wound surface that encloses nothing: every face has a twin wound the
    // other way (a double-sided export), or inward shells cancel the others. Its edges all pair
    // up, so nothing else would say that the mesh adds no mass.
    const bool encloses_nothing =
        !solids.empty() && geometry.topology().closed() && geometry.topology().consistently_oriented() &&
        solids.front().extent > 0 && std::isfinite(solids.front().extent) &&
        std::abs(solids.front().volume) <= kNoVolume * std::pow(solids.front().extent, 3);
    if (encloses_nothing) {
      diag.warning(codes::MESH_ENCLOSES_NO_VOLUME, pointer,
                   "mesh of '" + name + "' is closed but encloses no volume (" + format_number(solids.front().volume, 2) +
                       " m^3 across " + format_number(solids.front().extent, 3) +
                       " m): every face has a twin wound the other way (a mesh exported double-sided), or shells "
                       "wound inward cancel the others; it adds no mass. Export it single-sided, or remove the "
                       "reversed copies of its faces");
    }
    std::vector<int> signs;
    for (std::size_t k = 0; k < solids.size(); ++k) {
      VolumeIntegrals& integrals = solids[k];
      signs.push_back(integrals.volume < 0 ? -1 : 1);
      if (encloses_nothing) {
        // Exactly nothing: the sums' rounding (8e-14 kg, a moment of -1.7e-15 kg m^2) went into
        // every output as the link's mass and a tensor no body has, and its sign into a false
        // MESH_INSIDE_OUT (s100xform D4).
        integrals.volume = 0;
        integrals.second_central.setZero();
        continue;
      }
      integrals = oriented(integrals, pointer, name, diag, authored_by[static_cast<std::size_t>(link)],
                           solids.size() > 1 ? static_cast<int>(k) : -1);
      volume += integrals.volume;
    }
    double mesh_density = density;
    if (mass_override && volume > 0) {
      mesh_density = *mass_override / volume;
      mesh_masses[link].emplace_back(reported, *mass_override);
    }
    for (const VolumeIntegrals& integrals : solids) {
      pieces[link].push_back({integrals, mesh_density});
      robot.links[link].meshes.push_back({static_cast<int>(node), integrals.volume, mesh_density});
    }
    // Only surfaces the check found closed and consistently wound have a winding number to
    // sample; the others are warned about already (MESH_OPEN, MESH_INCONSISTENT_WINDING).
    const SurfaceTopology& topology = geometry.topology();
    if (topology.closed() && topology.consistently_oriented()) {
      for (std::size_t k = 0; k < instances->size(); ++k) {
        link_solids[link].push_back({geometry.pieces, X_LN * (*instances)[k], signs[k], reported,
                                     instances->size() > 1 ? static_cast<int>(k) : -1});
      }
    }
  }

  std::vector<std::size_t> no_volume;  // links without volume, in order
  for (std::size_t l = 0; l < robot.links.size(); ++l) {
    Link& link = robot.links[l];
    const std::string pointer = json_pointer("/nodes", link.node);
    for (const Json& child : document["nodes"][link.node].value("children", Json::array())) {
      if (types[child.get<std::size_t>()] == NodeType::kInertial) link.inertial_node = child.get<int>();
    }
    if (link.inertial_node >= 0) {
      // The extras.RDTF entry's inertial, else the inertial node's rdtf_inertial (what survives a
      // tool that keeps node extras only).
      const std::string label = node_label(document, static_cast<std::size_t>(link.inertial_node));
      const Json* entry = entries[static_cast<std::size_t>(link.inertial_node)];
      const std::string& entry_pointer = entry_pointers[static_cast<std::size_t>(link.inertial_node)];
      const Json& node = document["nodes"][link.inertial_node];
      std::optional<MassProperties> authored;
      if (entry != nullptr && entry->contains("inertial")) {
        const std::size_t errors_before = diag.error_count();
        authored = authored_inertial((*entry)["inertial"], entry_pointer + "/inertial", label, diag);
        // An entry refused above is not "computed from the geometry": nothing to compare with.
        if (diag.error_count() == errors_before) {
          link.ignored_inertial_extras = warn_if_extras_differ(node, authored, label, link.inertial_node, diag);
        }
      } else if (node.contains("extras") && node["extras"].is_object() &&
                 node["extras"].contains("rdtf_inertial")) {
        authored = authored_inertial(node["extras"]["rdtf_inertial"],
                                     json_pointer("/nodes", link.inertial_node) + "/extras/rdtf_inertial",
                                     label, diag);
      }
      if (authored) {
        link.inertial = *authored;
        link.inertial_source = InertialSource::kAuthored;
        continue;
      }
    }
    link.inertial = combine(pieces[l]);
    if (auto mass = positive_extra(document, link.node, "rdtf_mass", diag)) {
      if (link.inertial.mass > 0) {
        const double factor = *mass / link.inertial.mass;
        link.inertial.mass = *mass;
        link.inertial.inertia *= factor;
        // Every mesh's density scales alike, so that each mesh's density times its volume is
        // still its share of the link's mass (rdtf inspect lists them).
        for (LinkMesh& mesh : link.meshes) mesh.density *= factor;
        for (const auto& [node, mesh_mass] : mesh_masses[l]) {
          if (std::abs(factor - 1.0) <= 1e-12) continue;
          diag.warning(codes::RDTF_MASS_OVERRIDDEN, json_pointer("/nodes", node) + "/extras/rdtf_mass",
                       node_label(document, node) + " sets rdtf_mass " + format_number(mesh_mass) + " kg, but link '" +
                           link.name + "' sets rdtf_mass " + format_number(*mass) +
                           " kg for all its meshes, which scales this one to " + format_number(mesh_mass * factor) +
                           " kg; set the mass on the link or on its meshes, not both");
        }
      }
    }
    if (link.inertial.volume <= 0) no_volume.push_back(l);
  }
  // A link without volume is worth a word where it was meant to have some (it has meshes, and
  // none encloses any) or where its whole rigid body weighs nothing. A frame welded to a body that
  // has mass weighs nothing by design: an armature's own object, which holds the root bone by a
  // fixed joint (docs/blender.md), or a sensor frame. So does a root without meshes: the world's
  // frame (URDF's usual empty `world` link), which the gate holds fixed.
  if (!no_volume.empty()) {
    std::vector<bool> body_has_mass(robot.links.size(), false);
    for (const std::vector<std::size_t>& body : rigid_bodies(robot)) {
      bool mass = false;
      for (std::size_t l : body) mass = mass || robot.links[l].inertial.mass > 0;
      for (std::size_t l : body) body_has_mass[l] = mass;
    }
    std::vector<bool> is_root(robot.links.size(), true);
    for (const Joint& joint : robot.joints) {
      if (joint.child_link >= 0) is_root[static_cast<std::size_t>(joint.child_link)] = false;
    }
    for (std::size_t l : no_volume) {
      const Link& link = robot.links[l];
      const Json& node = document["nodes"][static_cast<std::size_t>(link.node)];
      // An rdtf_mass there is no mass: it scales the densities of the volume the meshes enclose.
      const bool mass_given = node.contains("extras") && node["extras"].is_object() &&
                              node["extras"].contains("rdtf_mass");
      // A meshless frame on a body with mass is what URDF keeps for a sensor, unless it was given
      // a mass (a payload's empty typed fixed): that mass would be dropped without a word.
      if (link.meshes.empty() && (body_has_mass[l] || is_root[l]) && !mass_given) continue;
      // A link without meshes whose node extras give it a density had meshes once: rdtf's output
      // of a part parented to a bone, exported again by Blender 3.4, which writes no children of
      // such an object (in the output a link's meshes are children of its node; docs/blender.md,
      // section 8). A meshless link alone proves nothing (a URDF's frame link, a typed empty).
      const bool lost = node.contains("extras") && node["extras"].is_object() &&
                        node["extras"].contains("rdtf_density");
      const std::string why =
          link.meshes.empty() ? (lost ? "no mesh, though its rdtf_density says it had one: if this is rdtf's output "
                                        "exported again by Blender, Blender 3.4 drops the children of an object "
                                        "parented to a bone, its mesh among them; edit the original .blend, not "
                                        "rdtf's output"
                                      : "no mesh")
          : flattened[l] ? "its meshes are scaled to nothing or enclose none"
          : link_solids[l].empty() ? "no closed mesh"
                                   : "its closed meshes enclose none: faces doubled back to back, or shells wound "
                                     "inward that cancel the others";
      diag.warning(codes::LINK_NO_VOLUME, json_pointer("/nodes", link.node),
                   "link '" + link.name + "' has no volume (" + why + "): its mass is zero" +
                       (mass_given ? ", and its rdtf_mass " + value_text(node["extras"]["rdtf_mass"]) +
                                         " is not applied: a mass fills the volume its meshes enclose, and there "
                                         "is none (" +
                                         (link.meshes.empty() ? std::string("give the link a closed mesh")
                                                              : std::string("close the mesh")) +
                                         ", or give the link an inertial in extras.RDTF)"
                                   : std::string()));
    }
  }
  if (solids_out == nullptr) report_part_overlaps(document, robot, own_solids, diag);
}

void report_part_overlaps(const Json& document, const Robot& robot, const LinkSolids& solids, Diagnostics& diag) {
  const auto& by_link = solids.state().by_link;
  internal::WindingScratch scratch;  // one model's bodies share the pages of their crossings
  for (const std::vector<std::size_t>& body : rigid_bodies(robot)) {
    // Every solid in the frame of the body's first link B.
    std::vector<internal::PlacedSolid> placed;
    std::vector<const LinkSolid*> owners;
    std::vector<std::size_t> owner_links;
    double volume = 0;
    for (std::size_t l : body) {
      const Link& link = robot.links[l];
      if (l >= by_link.size() || link.inertial_source == InertialSource::kAuthored) continue;
      const Eigen::Affine3d X_BL(robot.links[body.front()].X_SL.inverse() * link.X_SL);
      for (const LinkSolid& solid : by_link[l]) {
        placed.push_back({solid.pieces, X_BL * solid.X_LM, solid.orientation});
        owners.push_back(&solid);
        owner_links.push_back(l);
      }
      if (!by_link[l].empty()) volume += link.inertial.volume;
    }
    if (placed.empty()) continue;
    const internal::WindingSample sample = internal::sample_winding(placed, 4096, &scratch);
    // Judged against the body's volume, or where its solids' signed volumes cancel (an inward
    // shell as large as the rest), against the volume inside any of them.
    const double scale = std::max(volume, sample.covered);
    const double deficit_scale = std::max(volume, sample.deficit_covered);
    bool one_link = true;
    for (std::size_t k = 1; k < owner_links.size(); ++k) one_link = one_link && owner_links[k] == owner_links[0];
    const auto share = [&](double part, double of) {
      const double percent = 100 * part / of;
      return "about " + format_number(part, 2) + " m^3, " +
             (percent >= 10 ? std::to_string(static_cast<long long>(std::llround(percent))) : format_number(percent, 2)) +
             (one_link ? "% of its volume," : "% of its body's volume (the links fixed joints join),");
    };
    const auto body_of = [&](std::size_t a, std::size_t b) {
      const std::string& first = robot.links[owner_links[a]].name;
      const std::string& second = robot.links[owner_links[b]].name;
      if (first == second) return "link '" + first + "'";
      return "links '" + first + "' and '" + second + "' (one body: fixed joints join them)";
    };
    if (scale > 0 && sample.excess > kReportedVolumeFraction * scale && sample.excess_a >= 0) {
      const auto a = static_cast<std::size_t>(sample.excess_a), b = static_cast<std::size_t>(sample.excess_b);
      const std::string where =
          a == b ? "the mesh of " + solid_label(document, *owners[a]) +
                       " overlaps itself (parts joined into one object where they overlap, or a shell inside another "
                       "wound the same way)"
                 : "the meshes of " + solid_label(document, *owners[a]) + " and " + solid_label(document, *owners[b]) +
                       " overlap";
      diag.warning(codes::LINK_PARTS_OVERLAP, json_pointer("/nodes", owners[a]->node),
                   body_of(a, b) + ": " + where + ": " + share(sample.excess, scale) +
                       " is counted twice, and its mass and inertia with it; unite the parts (a Boolean Union "
                       "modifier, exported with Apply Modifiers), trim one to the other's surface, or flip an inner "
                       "shell's faces to make it a cavity");
    }
    if (deficit_scale > 0 && sample.deficit > kReportedVolumeFraction * deficit_scale && sample.deficit_solid >= 0) {
      const auto a = static_cast<std::size_t>(sample.deficit_solid);
      diag.warning(codes::MESH_SHELL_INSIDE_OUT, json_pointer("/nodes", owners[a]->node),
                   body_of(a, a) + ": the mesh of " + solid_label(document, *owners[a]) +
                       " has a shell wound inside out that lies outside its own solid: " + share(sample.deficit, deficit_scale) +
                       " is subtracted instead of added; recalculate its normals outside "
                       "(Blender: Mesh > Normals > Recalculate Outside)");
    }
  }
}

}  // namespace rdtf
