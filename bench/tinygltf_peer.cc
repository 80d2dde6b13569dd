// The tinygltf peer of `rdtf convert` and `rdtf inspect` for whole_process_bench: a plain program a
// user could write with tinygltf alone (images not decoded, as the synthetic models have none).
//   tinygltf_peer load IN.glb           load, print the triangle count of the first primitive
//   tinygltf_peer write IN.glb OUT.glb  load and write a GLB with every buffer embedded
// Exit 0 on success, 1 when tinygltf reports an error.
#include <tiny_gltf.h>

#include <cstdio>
#include <string>

namespace {

bool no_images(tinygltf::Image*, const int, std::string*, std::string*, int, int, const unsigned char*, int, void*) {
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string mode = argc >= 3 ? argv[1] : "";
  if (!((mode == "load" && argc == 3) || (mode == "write" && argc == 4))) {
    std::fprintf(stderr, "usage: tinygltf_peer load IN.glb | tinygltf_peer write IN.glb OUT.glb\n");
    return 2;
  }
  tinygltf::TinyGLTF gltf;
  gltf.SetImageLoader(&no_images, nullptr);
  tinygltf::Model model;
  std::string error, warning;
  if (!gltf.LoadBinaryFromFile(&model, &error, &warning, argv[2])) {
    std::fprintf(stderr, "tinygltf_peer: %s: %s\n", argv[2], error.c_str());
    return 1;
  }
  if (mode == "load") {
    const auto& primitive = model.meshes.at(0).primitives.at(0);
    std::printf("%zu triangles\n", model.accessors.at(static_cast<std::size_t>(primitive.indices)).count / 3);
    return 0;
  }
  if (!gltf.WriteGltfSceneToFile(&model, argv[3], /*embedImages=*/true, /*embedBuffers=*/true,
                                 /*prettyPrint=*/false, /*writeBinary=*/true)) {
    std::fprintf(stderr, "tinygltf_peer: cannot write %s\n", argv[3]);
    return 1;
  }
  return 0;
}
