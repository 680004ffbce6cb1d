// The built-in scenes of the simulator: one room with procedural textures (sim/textures.h).
#pragma once
#include <string>
#include <vector>

#include "sim/scene.h"

namespace evflow::sim {

// The project's default scene: an open room (textured floor, walls with text-like posters, a
// dark wall and a bright one) with boxes at several depths; procedural textures with fine detail.
// Cameras look at it from +z. Deterministic.
Scene make_default_scene();
// Built-in scenes by name: "default" (the above) and two variants of its room with other
// textures ("gallery": fine print and noise; "workshop": coarse bricks, gratings, dark corners),
// and "objects": three boxes (coarse checks, coarse bricks, a flat colour) on plain, untextured
// floor and walls.
Scene make_builtin_scene(const std::string& name);
std::vector<std::string> builtin_scene_names();
// A built-in scene by name, else a glTF file by path (sim/gltf_scene.h); empty: "default".
Scene builtin_or_gltf_scene(const std::string& name_or_path);
// The mean blur (pixels per exposure at 173 x 130) `evflow experiment` simulates a built-in scene
// with unless told otherwise: default 6, gallery 4 (its fine print is unreadable beyond), workshop
// 9 (coarse textures stay legible), objects 8; throws for another name.
double builtin_scene_blur_px(const std::string& name);

}  // namespace evflow::sim
