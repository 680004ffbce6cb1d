// Scenes in glTF 2.0 files (.gltf / .glb, via tinygltf): reading and writing.
#pragma once
#include <filesystem>

#include "sim/scene.h"

namespace evflow::sim {

// Reads a glTF 2.0 file (.gltf with external or embedded buffers/images, or .glb): every TRIANGLES
// primitive of the default scene (or all root nodes when there is none), node transforms
// applied, TEXCOORD_0 and the base-colour texture + factor of pbrMetallicRoughness (missing UVs =
// 0, missing material = white), and the camera-rig hint a written built-in scene carries in its
// scene's extras ("evflow_view"). Throws std::runtime_error naming the file on a missing or
// malformed file, an unsupported accessor, or a scene without triangles.
Scene load_gltf(const std::filesystem::path& path);

// Writes the scene as a binary glTF (.glb) with embedded PNG textures (or .gltf with embedded
// data URIs, by extension), with its camera-rig hint if it has one; temporary file, then rename.
void write_gltf(const Scene& scene, const std::filesystem::path& path);

}  // namespace evflow::sim
