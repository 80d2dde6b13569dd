#include <Eigen/SVD>

#include "rdtf/geometry.h"

namespace rdtf {

Eigen::Affine3d node_local_transform(const Json& node) {
  Eigen::Affine3d X = Eigen::Affine3d::Identity();
  if (node.contains("matrix")) {
    const Json& m = node["matrix"];
    Eigen::Matrix4d matrix;
    // glTF stores matrices column-major.
    for (int column = 0; column < 4; ++column) {
      for (int row = 0; row < 4; ++row) matrix(row, column) = m[column * 4 + row].get<double>();
    }
    X.matrix() = matrix;
    return X;
  }
  if (node.contains("translation")) {
    const Json& t = node["translation"];
    X.translate(Eigen::Vector3d(t[0].get<double>(), t[1].get<double>(), t[2].get<double>()));
  }
  if (node.contains("rotation")) {
    const Json& r = node["rotation"];
    // glTF quaternions are (x, y, z, w); normalise, as viewers do, against float rounding.
    Eigen::Quaterniond q(r[3].get<double>(), r[0].get<double>(), r[1].get<double>(),
                         r[2].get<double>());
    if (q.norm() > 0) q.normalize();
    X.rotate(q);
  }
  if (node.contains("scale")) {
    const Json& s = node["scale"];
    X.scale(Eigen::Vector3d(s[0].get<double>(), s[1].get<double>(), s[2].get<double>()));
  }
  return X;
}

std::vector<int> node_parents(const Json& document) {
  const std::size_t count = document.contains("nodes") ? document["nodes"].size() : 0;
  std::vector<int> parent(count, -1);
  for (std::size_t i = 0; i < count; ++i) {
    const Json& node = document["nodes"][i];
    if (!node.contains("children")) continue;
    for (const Json& child : node["children"]) parent[child.get<std::size_t>()] = static_cast<int>(i);
  }
  return parent;
}

std::vector<Eigen::Affine3d> node_world_transforms(const Json& document) {
  const std::size_t count = document.contains("nodes") ? document["nodes"].size() : 0;
  std::vector<Eigen::Affine3d> world(count, Eigen::Affine3d::Identity());
  std::vector<char> done(count, 0);
  // Roots first, then children: an explicit stack, as the tree may be deep.
  std::vector<std::pair<std::size_t, Eigen::Affine3d>> stack;
  const auto parents = node_parents(document);
  for (std::size_t i = 0; i < count; ++i) {
    if (parents[i] < 0) stack.emplace_back(i, Eigen::Affine3d::Identity());
  }
  while (!stack.empty()) {
    auto [index, X_SP] = stack.back();
    stack.pop_back();
    if (done[index]) continue;
    done[index] = 1;
    const Json& node = document["nodes"][index];
    world[index] = X_SP * node_local_transform(node);
    if (node.contains("children")) {
      for (const Json& child : node["children"]) stack.emplace_back(child.get<std::size_t>(), world[index]);
    }
  }
  return world;
}

Eigen::Matrix3d orthogonal_part(const Eigen::Matrix3d& A) {
  if ((A.transpose() * A - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() < 1e-12) return A;
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(A, Eigen::ComputeFullU | Eigen::ComputeFullV);
  return svd.matrixU() * svd.matrixV().transpose();
}

Eigen::Isometry3d rigid_part(const Eigen::Affine3d& X) {
  Eigen::Isometry3d rigid = Eigen::Isometry3d::Identity();
  rigid.translation() = X.translation();
  Eigen::Matrix3d Q = orthogonal_part(X.linear());
  // A mirror is not a rotation: the frame's Z axis reversed makes it one. (Flipping the axis of the
  // smallest singular value, as before, left the frame to the SVD's order when the scales tie, as
  // Blender's mirrored wheel's -1, 1, 1 do: s101fmt D4.)
  if (Q.determinant() < 0) Q.col(2) = -Q.col(2);
  rigid.linear() = Q;
  return rigid;
}

}  // namespace rdtf
