// Pieces shared by URDF export and import (not public API).
#pragma once

#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <urdf_model/model.h>

#include "rdtf/diagnostics.h"
#include "rdtf/gltf.h"
#include "rdtf/robot.h"
#include "rdtf/triangle_mesh.h"

namespace rdtf::urdf_internal {

// The rotation from glTF's Y-up axes to ROS's Z-up axes: +90 degrees about X, (x, y, z) ->
// (x, -z, y). Its entries are 0 and +-1, so applying it is exact in floating point.
Eigen::Matrix3d y_up_to_z_up();

// A change of axes C applied to every frame: poses X -> C X C^T, vectors v -> C v, tensors
// I -> C I C^T.
Eigen::Isometry3d conjugate(const Eigen::Matrix3d& C, const Eigen::Isometry3d& X);

// URDF's roll-pitch-yaw (R = Rz(yaw) Ry(pitch) Rx(roll)) of a rotation matrix, and back.
Eigen::Vector3d rpy_from_rotation(const Eigen::Matrix3d& R);
Eigen::Matrix3d rotation_from_rpy(const Eigen::Vector3d& rpy);

// The shortest decimal text that reads back as exactly the same double ("0.1", "1e-20"); -0 is
// written as 0.
std::string exact_number(double value);

// A URDF name from any text: ASCII letters, digits, '_', '-' and '.' kept, any other character
// (a UTF-8 sequence counts once) '_'; never empty (`fallback`).
std::string valid_urdf_name(const std::string& text, const std::string& fallback);

// Makes `name` unique among `taken` (appending _2, _3, ...) and records it.
std::string unique_name(const std::string& name, std::vector<std::string>& taken);

// The triangles of each link's meshes, in the link frame (glTF axes), wound outward (mirrored and
// inside-out solids turned right). `closed` is false when any solid of the link is open or has no
// volume: such a mesh is no collision geometry (MuJoCo refuses meshes without volume).
struct LinkSurface {
  TriangleMesh mesh;
  bool closed = true;
  std::size_t solids = 0;
};
std::vector<LinkSurface> link_surfaces(const GltfAsset& asset, const Robot& robot);

// Runs `body` with urdfdom's console_bridge messages captured (one lock for the whole process:
// console_bridge's handler is global) and returns them, one per line.
std::string with_console_captured(const std::function<void()>& body);

// urdfdom's Link owns its children (child_links): a model whose root is freed last frees a chain
// with one nested destructor per link, and 20,000 links overflowed a 1 MiB stack, 200,000 the
// default 8 MiB (s103env D4). Held over a model, this clears every link's child lists when it
// goes, so that the model's map then frees the links one by one.
class FlatRelease {
 public:
  explicit FlatRelease(const std::shared_ptr<urdf::ModelInterface>& model) : model_(model) {}
  FlatRelease(const FlatRelease&) = delete;
  FlatRelease& operator=(const FlatRelease&) = delete;
  ~FlatRelease();

 private:
  const std::shared_ptr<urdf::ModelInterface>& model_;
};

}  // namespace rdtf::urdf_internal
