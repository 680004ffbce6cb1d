// Included first by every header shared between C++ and GLSL: lets one struct definition
// compile on both sides (std430 / push-constant layout: only 4-byte scalars and vec4s).
// EVF_BIND(name, index, Block) names a storage-buffer binding of a kernel: in GLSL the constant
// `name` for `layout(std430, binding = name) buffer Block`, in C++ a BindSlot carrying the index
// and the block's name, which gpu::Commands::dispatch checks against the kernel's SPIR-V.
#ifndef EVF_SHARED_PRELUDE_H
#define EVF_SHARED_PRELUDE_H
#ifdef __cplusplus
#include <cstdint>
#include <glm/glm.hpp>
namespace evflow::shaderio {
struct BindSlot {
  uint32_t index;
  const char* block;  // the GLSL block's type name
};
}  // namespace evflow::shaderio
#define EVF_NAMESPACE_BEGIN namespace evflow::shaderio { using uint = uint32_t; using glm::vec4; using glm::uvec4;
#define EVF_NAMESPACE_END }
#define EVF_CONST(type, name, value) inline constexpr type name = value;
#define EVF_BIND(name, index, block) inline constexpr BindSlot name{index, #block};
#else
#define EVF_NAMESPACE_BEGIN
#define EVF_NAMESPACE_END
#define EVF_CONST(type, name, value) const type name = value;
#define EVF_BIND(name, index, block) const uint name = index;
#endif
#endif
