// Lets a header compile as GLSL and as C++ (GLM), so layouts and pure per-cell functions are written once.
#ifndef GUST_SHADERS_COMMON_H
#define GUST_SHADERS_COMMON_H

#ifdef __cplusplus
#include <cstdint>
#include <glm/glm.hpp>
#define GUST_NAMESPACE_BEGIN                                                                                 \
    namespace gust::shaderio {                                                                               \
    using namespace glm;                                                                                     \
    using uint = std::uint32_t;
#define GUST_NAMESPACE_END }
#define GUST_INLINE inline
#define GUST_CONST inline constexpr
#define GUST_ADDRESS std::uint64_t
#define GUST_OUT(type) type&
#define GUST_INOUT(type) type&
#else
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_scalar_block_layout : require
#define GUST_NAMESPACE_BEGIN
#define GUST_NAMESPACE_END
#define GUST_INLINE
#define GUST_CONST const
#define GUST_ADDRESS uint64_t
#define GUST_OUT(type) out type
#define GUST_INOUT(type) inout type
#endif

#endif
