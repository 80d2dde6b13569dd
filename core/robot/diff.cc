#include "rdtf/diff.h"

#include <algorithm>
#include <cstring>
#include <map>
#include <utility>

#include "rdtf/geometry.h"

namespace rdtf {
namespace {

template <std::size_t N>
bool same(const double (&a)[N], const double (&b)[N]) {
  // Exact: bit for bit equal doubles (and -0 == 0, which no content tells apart).
  for (std::size_t i = 0; i < N; ++i) {
    if (!(a[i] == b[i])) return false;
  }
  return true;
}

std::uint32_t link_aspects(const LinkFacts& a, const LinkFacts& b) {
  std::uint32_t aspects = 0;
  if (!(a.mass == b.mass) || !(a.volume == b.volume) || !same(a.center_of_mass, b.center_of_mass) ||
      !same(a.inertia, b.inertia) || a.authored != b.authored) {
    aspects |= kAspectInertial;
  }
  if (a.geometry != b.geometry) aspects |= kAspectGeometry;
  if (a.parent_joint != b.parent_joint) aspects |= kAspectParent;
  return aspects;
}

std::uint32_t joint_aspects(const JointFacts& a, const JointFacts& b) {
  std::uint32_t aspects = 0;
  if (!same(a.origin, b.origin)) aspects |= kAspectOrigin;
  if (!same(a.axis, b.axis)) aspects |= kAspectAxis;
  if (a.type != b.type) aspects |= kAspectType;
  if (a.has_limits != b.has_limits || a.has_range != b.has_range || (a.has_limits && !same(a.limits, b.limits))) {
    aspects |= kAspectLimits;
  }
  if (!same(a.dynamics, b.dynamics)) aspects |= kAspectDynamics;
  if (a.parent != b.parent) aspects |= kAspectParent;
  if (a.child != b.child) aspects |= kAspectChild;
  return aspects;
}

// Each element's key: its name and which occurrence of that name it is.
template <typename Facts>
std::vector<std::pair<std::string, int>> keys_of(const std::vector<Facts>& elements) {
  std::map<std::string, int> seen;
  std::vector<std::pair<std::string, int>> keys;
  keys.reserve(elements.size());
  for (const Facts& e : elements) keys.emplace_back(e.name, seen[e.name]++);
  return keys;
}

template <typename Facts, typename Compare>
void diff_elements(const std::vector<Facts>& before, const std::vector<Facts>& after,
                   ElementChange::Element element, Compare compare, std::vector<ElementChange>& out) {
  const auto keys_before = keys_of(before);
  const auto keys_after = keys_of(after);
  std::map<std::pair<std::string, int>, std::size_t> index_after;
  for (std::size_t i = 0; i < keys_after.size(); ++i) index_after.emplace(keys_after[i], i);
  std::map<std::pair<std::string, int>, std::size_t> index_before;
  for (std::size_t i = 0; i < keys_before.size(); ++i) index_before.emplace(keys_before[i], i);
  for (std::size_t i = 0; i < before.size(); ++i) {
    if (index_after.count(keys_before[i]) == 0) {
      out.push_back({element, ElementChange::Kind::kRemoved, before[i].name, before[i].urdf_name, 0});
    }
  }
  for (std::size_t i = 0; i < after.size(); ++i) {
    const auto found = index_before.find(keys_after[i]);
    if (found == index_before.end()) continue;
    const std::uint32_t aspects = compare(before[found->second], after[i]);
    if (aspects != 0) out.push_back({element, ElementChange::Kind::kChanged, after[i].name, after[i].urdf_name, aspects});
  }
  for (std::size_t i = 0; i < after.size(); ++i) {
    if (index_before.count(keys_after[i]) == 0) {
      out.push_back({element, ElementChange::Kind::kAdded, after[i].name, after[i].urdf_name, 0});
    }
  }
}

void append_doubles(std::vector<std::uint8_t>& bytes, const double* values, std::size_t count) {
  const auto* begin = reinterpret_cast<const std::uint8_t*>(values);
  bytes.insert(bytes.end(), begin, begin + count * sizeof(double));
}

void append_text(std::vector<std::uint8_t>& bytes, const std::string& text) {
  const std::uint64_t size = text.size();
  const auto* begin = reinterpret_cast<const std::uint8_t*>(&size);
  bytes.insert(bytes.end(), begin, begin + sizeof(size));
  bytes.insert(bytes.end(), text.begin(), text.end());
}

// The digest of `count` elements of `size` bytes, `stride` bytes apart: read where they lie when
// they are dense (what exporters write), so a large mesh is not copied to be hashed.
std::string strided_digest(const std::uint8_t* base, std::size_t stride, std::size_t size, std::size_t count,
                           const ContentDigest& digest) {
  if (base == nullptr || count == 0) return digest({});
  if (stride == size) return digest(std::span<const std::uint8_t>(base, size * count));
  std::vector<std::uint8_t> dense;
  dense.reserve(size * count);
  for (std::size_t i = 0; i < count; ++i) dense.insert(dense.end(), base + i * stride, base + i * stride + size);
  return digest(dense);
}

// The digest of one mesh: every primitive's positions and triangles as the mass computation reads
// them (in place as stored, or as the copy it makes of strips, fans and sparse accessors).
std::string mesh_digest(const GltfAsset& asset, std::size_t mesh, std::span<const double> weights,
                        const ContentDigest& digest) {
  std::vector<std::uint8_t> bytes;
  Diagnostics ignored;  // The conversion reported these already.
  const Json& primitives = asset.document["meshes"][mesh]["primitives"];
  for (std::size_t p = 0; p < primitives.size(); ++p) {
    const auto triangles = read_primitive_in_place(asset, mesh, p, ignored, weights);
    if (!triangles) {
      bytes.push_back(0);
      continue;
    }
    const TriangleMeshView v = triangles->view();
    const std::size_t position_size = 3 * (v.position_type == TriangleMeshView::Positions::kFloat32 ? 4 : 8);
    static constexpr std::size_t kIndexSize[] = {0, 1, 2, 4};
    const std::size_t index_size = kIndexSize[static_cast<int>(v.index_type)];
    const std::uint64_t header[4] = {v.vertex_count, v.triangle_count, position_size, index_size};
    const auto* header_bytes = reinterpret_cast<const std::uint8_t*>(header);
    bytes.push_back(1);
    bytes.insert(bytes.end(), header_bytes, header_bytes + sizeof(header));
    append_text(bytes, strided_digest(v.positions, v.position_stride, position_size, v.vertex_count, digest));
    if (index_size > 0) {
      append_text(bytes, strided_digest(v.indices, v.index_stride, index_size, 3 * v.triangle_count, digest));
    }
  }
  return digest(bytes);
}

// Where a solid lies in its link frame. For a node at or below the link node: the local transforms
// from below the link node down to it, which do not depend on where the link is, so an edit of an
// upstream joint origin (which moves the link) leaves them bit for bit alone. For any other node
// (a skinned mesh, a mesh placed elsewhere): its transform in the link frame, X_LN.
void append_placement(std::vector<std::uint8_t>& bytes, const Json& document, const std::vector<int>& parents,
                      const std::vector<Eigen::Affine3d>& world, const Link& link, int node) {
  std::vector<int> chain;
  int at = node;
  while (at >= 0 && at != link.node && chain.size() <= parents.size()) {
    chain.push_back(at);
    at = static_cast<std::size_t>(at) < parents.size() ? parents[static_cast<std::size_t>(at)] : -1;
  }
  if (at == link.node && link.node >= 0) {
    const std::uint8_t below = 1;
    bytes.push_back(below);
    for (auto it = chain.rbegin(); it != chain.rend(); ++it) {
      const Eigen::Affine3d X = node_local_transform(document["nodes"][static_cast<std::size_t>(*it)]);
      append_doubles(bytes, X.matrix().data(), 16);
    }
    return;
  }
  bytes.push_back(0);
  const Eigen::Affine3d X_LN = link.X_SL.inverse() * world[static_cast<std::size_t>(node)];
  append_doubles(bytes, X_LN.matrix().data(), 16);
}

}  // namespace

RobotFacts robot_facts(const Robot& robot, const std::vector<std::string>& urdf_link_names,
                       const std::vector<std::string>& urdf_joint_names,
                       const std::vector<std::string>& link_geometry) {
  RobotFacts facts;
  auto joint_name = [&](int joint) {
    return joint >= 0 && static_cast<std::size_t>(joint) < robot.joints.size() ? robot.joints[joint].name : std::string();
  };
  auto link_name = [&](int link) {
    return link >= 0 && static_cast<std::size_t>(link) < robot.links.size() ? robot.links[link].name : std::string();
  };
  for (std::size_t l = 0; l < robot.links.size(); ++l) {
    const Link& link = robot.links[l];
    LinkFacts f;
    f.name = link.name;
    f.urdf_name = l < urdf_link_names.size() ? urdf_link_names[l] : link.name;
    f.parent_joint = joint_name(link.parent_joint);
    f.mass = link.inertial.mass;
    f.volume = link.inertial.volume;
    for (int i = 0; i < 3; ++i) f.center_of_mass[i] = link.inertial.center_of_mass[i];
    const auto& I = link.inertial.inertia;
    const double inertia[6] = {I(0, 0), I(0, 1), I(0, 2), I(1, 1), I(1, 2), I(2, 2)};
    std::copy(inertia, inertia + 6, f.inertia);
    f.authored = link.inertial_source == InertialSource::kAuthored;
    f.geometry = l < link_geometry.size() ? link_geometry[l] : std::string();
    facts.links.push_back(std::move(f));
  }
  for (std::size_t j = 0; j < robot.joints.size(); ++j) {
    const Joint& joint = robot.joints[j];
    JointFacts f;
    f.name = joint.name;
    f.urdf_name = j < urdf_joint_names.size() ? urdf_joint_names[j] : joint.name;
    f.type = to_string(joint.kind);
    f.parent = link_name(joint.parent_link);
    f.child = link_name(joint.child_link);
    const Eigen::Matrix3d R = joint.X_PJ.rotation();
    const Eigen::Vector3d p = joint.X_PJ.translation();
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) f.origin[3 * r + c] = R(r, c);
      f.origin[9 + r] = p[r];
      f.axis[r] = joint.axis[r];
    }
    f.has_limits = joint.limits.has_value();
    f.has_range = joint.limits && joint.limits->position;
    if (joint.limits) {
      const double limits[4] = {joint.limits->lower, joint.limits->upper, joint.limits->effort, joint.limits->velocity};
      std::copy(limits, limits + 4, f.limits);
    }
    f.dynamics[0] = joint.damping;
    f.dynamics[1] = joint.friction;
    f.dynamics[2] = joint.spring_stiffness;
    facts.joints.push_back(std::move(f));
  }
  return facts;
}

std::vector<std::string> link_geometry_digests(const GltfAsset& asset, const Robot& robot,
                                               const ContentDigest& digest) {
  std::vector<std::string> digests(robot.links.size());
  const Json& document = asset.document;
  if (!document.contains("nodes") || !document["nodes"].is_array()) return digests;
  const auto world = node_world_transforms(document);
  const auto parents = node_parents(document);
  // A mesh shared by several nodes (with the same morph weights) is read once.
  std::map<std::pair<std::size_t, std::vector<double>>, std::string> meshes;
  for (std::size_t l = 0; l < robot.links.size(); ++l) {
    const Link& link = robot.links[l];
    std::vector<std::uint8_t> bytes;
    std::vector<int> done;
    for (const LinkMesh& link_mesh : link.meshes) {
      const int node = link_mesh.node;
      if (node < 0 || static_cast<std::size_t>(node) >= world.size()) continue;
      if (std::find(done.begin(), done.end(), node) != done.end()) continue;
      done.push_back(node);
      const Json& n = document["nodes"][static_cast<std::size_t>(node)];
      if (!n.contains("mesh") || !n["mesh"].is_number_unsigned()) continue;
      const auto mesh = n["mesh"].get<std::size_t>();
      auto key = std::make_pair(mesh, morph_weights(document, static_cast<std::size_t>(node)));
      auto found = meshes.find(key);
      if (found == meshes.end()) {
        const std::string mesh_bytes = mesh_digest(asset, mesh, key.second, digest);
        found = meshes.emplace(std::move(key), mesh_bytes).first;
      }
      append_placement(bytes, document, parents, world, link, node);
      append_text(bytes, found->second);
      if (n.contains("skin") && n["skin"].is_number_unsigned()) {
        const Json& skin = document["skins"][n["skin"].get<std::size_t>()];
        if (skin.contains("inverseBindMatrices") && skin["inverseBindMatrices"].is_number_unsigned()) {
          const auto matrices = read_accessor(asset, skin["inverseBindMatrices"].get<std::size_t>());
          append_doubles(bytes, matrices.data(), matrices.size());
        }
      }
    }
    digests[l] = digest(bytes);
  }
  return digests;
}

std::vector<std::string> aspect_names(std::uint32_t aspects) {
  static const char* const kNames[] = {"origin", "axis", "type", "limits", "dynamics",
                                       "inertial", "geometry", "parent", "child"};
  std::vector<std::string> names;
  for (std::uint32_t bit = 0; bit < std::size(kNames); ++bit) {
    if (aspects & (1u << bit)) names.emplace_back(kNames[bit]);
  }
  return names;
}

const char* to_string(ElementChange::Element element) {
  return element == ElementChange::Element::kLink ? "link" : "joint";
}

const char* to_string(ElementChange::Kind kind) {
  switch (kind) {
    case ElementChange::Kind::kAdded:
      return "added";
    case ElementChange::Kind::kRemoved:
      return "removed";
    case ElementChange::Kind::kChanged:
      return "changed";
  }
  return "?";
}

std::vector<ElementChange> diff_robots(const RobotFacts& before, const RobotFacts& after) {
  std::vector<ElementChange> changes;
  diff_elements(before.links, after.links, ElementChange::Element::kLink, link_aspects, changes);
  diff_elements(before.joints, after.joints, ElementChange::Element::kJoint, joint_aspects, changes);
  return changes;
}

}  // namespace rdtf
