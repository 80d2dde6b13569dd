// Converts Khronos' Box.gltf (a unit cube, 1 m^3) with the installed librdtf and checks its mass
// properties at the default density 1000 kg/m^3: mass 1000 kg, centre of mass at the origin, and
// the solid cube's inertia m/6 = 166.666... kg m^2 about each axis.
// Usage: rdtf_consumer Box.gltf   (exit 0 when every value matches)
#include <cmath>
#include <cstdio>

#include <rdtf/convert.h>
#include <rdtf/version.h>

namespace {

bool close(double actual, double expected, const char* what) {
  const bool ok = std::abs(actual - expected) <= 1e-9 * std::abs(expected) + 1e-12;
  std::printf("%s %s: %.15g (expected %.15g)\n", ok ? "ok  " : "FAIL", what, actual, expected);
  return ok;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: rdtf_consumer Box.gltf\n");
    return 2;
  }
  std::printf("librdtf %s (commit %s)\n", rdtf::version(), rdtf::git_commit());
  rdtf::Diagnostics diagnostics;
  const auto conversion = rdtf::convert_file(argv[1], rdtf::ConvertOptions{}, diagnostics);
  if (!conversion || conversion->robot.links.size() != 1) {
    std::fprintf(stderr, "FAIL: %s did not convert to one link\n", argv[1]);
    return 1;
  }
  const rdtf::MassProperties& inertial = conversion->robot.links[0].inertial;
  bool ok = close(inertial.mass, 1000.0, "mass kg");
  ok &= close(inertial.center_of_mass.norm() + 1.0, 1.0, "1 + |centre of mass| m");
  for (int axis = 0; axis < 3; ++axis) {
    ok &= close(inertial.inertia(axis, axis), 1000.0 / 6.0, "principal inertia kg m^2");
    ok &= close(inertial.inertia(axis, (axis + 1) % 3) + 1.0, 1.0, "1 + product of inertia kg m^2");
  }
  return ok ? 0 : 1;
}
