// Procedural textures of the built-in scenes: linear-light patterns with fine detail, encoded to
// sRGB RGBA8. Deterministic.
#pragma once
#include <array>
#include <cstdint>

#include "sim/scene.h"

namespace evflow::sim {

// Paper with rows of glyph-like strokes (text): 5x7 cells of random bars, a large headline row.
Texture text_texture(uint32_t seed, double paper, double ink, const std::array<double, 3>& tint);
Texture checker_texture();
Texture brick_texture();
Texture noise_texture(uint32_t seed);
Texture grating_texture();
Texture dark_texture();

}  // namespace evflow::sim
