// The residual prior's training scenes: procedural rooms drawn from a seed, disjoint from every
// evaluation scene (the simulator's built-in default, gallery, workshop and objects). A room has
// a floor, three walls and 3 to 6 boxes at random places and sizes; each surface gets one of the
// simulator's procedural textures (text, noise, checks, bricks, grating, dark) with a random tint
// and tiling, the text and noise textures from seeds of their own (>= 1000, none of which a
// built-in scene uses). Deterministic for a seed.
#pragma once
#include <cstdint>

#include "sim/scene.h"

namespace evflow::prior {

sim::Scene make_training_room(uint64_t seed);

}  // namespace evflow::prior
