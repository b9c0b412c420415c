// glTF internals shared by load_mesh and AnimatedMesh: parsing after schema checks, bounds-checked
// accessor reads, and the node walk that places the geometry. Failure messages are bare reasons.
#pragma once

#include "gust/gpu/result.hpp"
#include "gust/scene/mesh.hpp"

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>
#include <string>
#include <string_view>
#include <tiny_gltf.h>
#include <vector>

namespace gust::detail {

/// Whether `bytes` begin as a GLB file does ("glTF").
bool is_glb(const std::vector<unsigned char>& bytes);

/// The JSON text of a .gltf file or of a GLB's first chunk, after checking the GLB framing.
/// Defined in gltf_schema.cpp.
Result<std::string_view> json_text(const std::vector<unsigned char>& bytes);

/// Checks `text` against the property types of the glTF 2.0 core schema (the names tinygltf would drop
/// or misread) and its required extensions against those that leave the geometry as it is.
/// Defined in gltf_schema.cpp.
Status check_json(std::string_view text);

/// Parses the glTF or GLB file held in `bytes` after checking its JSON against the core schema's
/// property types and its required extensions; external buffers are read from next to `path`.
Result<tinygltf::Model> parse_gltf(const std::vector<unsigned char>& bytes,
                                   const std::filesystem::path& path);

/// A run of vertices of the built mesh that came from one POSITION accessor of one mesh instance.
struct GltfVertexBlock {
    int node = -1;             ///< the node that instanced the mesh
    std::size_t mesh = 0;      ///< index into Model::meshes
    std::size_t primitive = 0; ///< the first primitive of that mesh that used the POSITION accessor
    std::uint32_t first = 0;   ///< first vertex in Mesh::positions
    std::uint32_t count = 0;   ///< number of vertices
};

/// The triangles of a glTF scene as load_mesh returns them, with where each vertex came from and the
/// walk that placed it (so that the same placement can be evaluated again with animated nodes).
struct GltfGeometry {
    Mesh mesh;                           ///< what load_mesh returns (unnamed)
    std::vector<GltfVertexBlock> blocks; ///< in vertex order, covering every vertex once
    std::vector<int> parent;             ///< each node's parent in the file's hierarchy; -1 for roots
    std::vector<int> walk_order;         ///< the nodes the walk reached, each after its walk_parent
    /// The node the walk reached each node from; -1 where the walk started or never came. It differs
    /// from `parent` where a file lists a child node as a scene root (the walk starts it from identity).
    std::vector<int> walk_parent;
};

/// Triangulates the default scene of `model` (file of `file_size` bytes): node transforms applied,
/// skinned meshes as raw POSITION data, points and lines dropped. Checks the node hierarchy first.
Result<GltfGeometry> build_gltf(const tinygltf::Model& model, std::size_t file_size);

/// The triangles of the default scene of `model` as a glTF viewer shows the file without animation:
/// build_gltf's, with every skinned mesh in its rest pose (its joints placed by the nodes' own
/// transforms, then linear-blend skinning as glTF 2.0 section 3.7.3 defines it). Checks the skins too.
/// Defined in animated_mesh.cpp, beside the skinning.
Result<Mesh> gltf_rest_pose(const tinygltf::Model& model, std::size_t file_size);

/// The node's local transform: its matrix, or translation · rotation (normalised) · scale.
glm::dmat4 local_transform(const tinygltf::Node& node);

/// translation · rotation (normalised; identity when of zero length) · scale, composed exactly as
/// local_transform composes a node's TRS properties.
glm::dmat4 trs_matrix(const glm::dvec3& translation, glm::dquat rotation, const glm::dvec3& scale);

/// Where one primitive is, for messages: "mesh 'Cube' primitive 0" (or "mesh 3 primitive 0").
std::string primitive_name(const tinygltf::Model& model, std::size_t mesh, std::size_t primitive);

/// `size` bytes at `offset` inside buffer view `view`, or a failure naming `what`.
Result<const unsigned char*> view_bytes(const tinygltf::Model& model, int view, std::uint64_t offset,
                                        std::uint64_t size, const std::string& what);

/// Reads every element of accessor `index` with `decode(bytes)`, sparse substitutions applied.
/// Accessors without a buffer view are zero-filled; their count is limited to the file size so that a
/// bare count cannot demand unbounded memory.
template <class T, class Decode>
Result<std::vector<T>> read_accessor(const tinygltf::Model& model, int index, std::size_t file_size,
                                     Decode decode) {
    using R = Result<std::vector<T>>;
    const std::string what = "accessor " + std::to_string(index);
    if (index < 0 || static_cast<std::size_t>(index) >= model.accessors.size()) {
        return R::failure(what + " does not exist");
    }
    const tinygltf::Accessor& accessor = model.accessors[static_cast<std::size_t>(index)];
    const int component =
        tinygltf::GetComponentSizeInBytes(static_cast<std::uint32_t>(accessor.componentType));
    const int components = tinygltf::GetNumComponentsInType(static_cast<std::uint32_t>(accessor.type));
    if (component <= 0 || components <= 0) return R::failure(what + " has an invalid type");
    const auto element = static_cast<std::uint64_t>(component) * static_cast<std::uint64_t>(components);
    const std::uint64_t count = accessor.count;

    std::vector<T> out;
    if (accessor.bufferView >= 0) {
        if (static_cast<std::size_t>(accessor.bufferView) >= model.bufferViews.size()) {
            return R::failure(what + " refers to missing buffer view " + std::to_string(accessor.bufferView));
        }
        const tinygltf::BufferView& bv = model.bufferViews[static_cast<std::size_t>(accessor.bufferView)];
        const std::uint64_t stride = bv.byteStride != 0 ? bv.byteStride : element;
        if (stride < element) return R::failure(what + " has a byte stride smaller than its elements");
        if (count > 0) {
            // Compared before multiplying so that a huge count cannot overflow the byte span.
            if (count - 1 > bv.byteLength / stride) {
                return R::failure(what + " reads past the end of buffer view " +
                                  std::to_string(accessor.bufferView));
            }
            Result<const unsigned char*> bytes = view_bytes(model, accessor.bufferView, accessor.byteOffset,
                                                            (count - 1) * stride + element, what);
            if (!bytes) return bytes.status();
            out.reserve(static_cast<std::size_t>(count));
            for (std::uint64_t i = 0; i < count; ++i) {
                out.push_back(decode(*bytes + i * stride));
            }
        }
    } else if (count > file_size) {
        return R::failure(what + " has no buffer view and " + std::to_string(count) +
                          " elements, more than the file could describe");
    } else {
        out.assign(static_cast<std::size_t>(count), T{});
    }

    if (!accessor.sparse.isSparse) return out;
    const auto& sparse = accessor.sparse;
    const auto sparse_count = static_cast<std::uint64_t>(sparse.count);
    if (sparse.count < 0 || sparse_count > count) return R::failure(what + " has an invalid sparse count");
    const int sparse_type = sparse.indices.componentType;
    if (sparse_type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE &&
        sparse_type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
        sparse_type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT) {
        return R::failure(what + " has an invalid sparse index type");
    }
    const auto index_size =
        static_cast<std::size_t>(tinygltf::GetComponentSizeInBytes(static_cast<std::uint32_t>(sparse_type)));
    Result<const unsigned char*> indices =
        view_bytes(model, sparse.indices.bufferView, static_cast<std::uint64_t>(sparse.indices.byteOffset),
                   sparse_count * index_size, what + " sparse indices");
    if (!indices) return indices.status();
    Result<const unsigned char*> values =
        view_bytes(model, sparse.values.bufferView, static_cast<std::uint64_t>(sparse.values.byteOffset),
                   sparse_count * element, what + " sparse values");
    if (!values) return values.status();
    for (std::uint64_t i = 0; i < sparse_count; ++i) {
        std::uint64_t target = 0;
        for (std::size_t b = index_size; b-- > 0;) { // little-endian
            target = (target << 8) | (*indices)[i * index_size + b];
        }
        if (target >= count) return R::failure(what + " has a sparse index out of range");
        out[static_cast<std::size_t>(target)] = decode(*values + i * element);
    }
    return out;
}

} // namespace gust::detail
