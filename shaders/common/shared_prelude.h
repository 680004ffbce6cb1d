// Included first by every header shared between C++ and GLSL: lets one struct definition
// compile on both sides (std430 / push-constant layout: only 4-byte scalars and vec4s).
#ifndef EVF_SHARED_PRELUDE_H
#define EVF_SHARED_PRELUDE_H
#ifdef __cplusplus
#include <cstdint>
#include <glm/glm.hpp>
#define EVF_NAMESPACE_BEGIN namespace evflow::shaderio { using uint = uint32_t; using glm::vec4; using glm::uvec4;
#define EVF_NAMESPACE_END }
#define EVF_CONST(type, name, value) inline constexpr type name = value;
#else
#define EVF_NAMESPACE_BEGIN
#define EVF_NAMESPACE_END
#define EVF_CONST(type, name, value) const type name = value;
#endif
#endif
