// Mesh file import for tools, tests and the sample: one triangle list per file, never an exception.
#pragma once

#include "gust/gpu/result.hpp"
#include "gust/scene/mesh.hpp"

#include <filesystem>

namespace gust {

/// Loads every triangle of the mesh file at `path` (.ply, .obj, .stl through Assimp; .gltf, .glb
/// through tinygltf) as one indexed triangle list in the file's scene space and units: node transforms
/// applied, skinned meshes in their rest pose (as a glTF viewer shows the file), points and lines dropped,
/// strips and fans expanded. The mesh is named after the file name. Non-finite positions are kept (the
/// voxelizer rejects those triangles). On failure the message is "<path>: <reason>"; it never throws. Safe to
/// call from several threads at once.
Result<Mesh> load_mesh(const std::filesystem::path& path);

/// Checks that `mesh.indices` holds whole triangles and that every index is below
/// `mesh.positions.size()`; positions are not inspected. The message starts with `mesh.name`.
Status validate_mesh(const Mesh& mesh);

} // namespace gust
