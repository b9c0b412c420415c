// Format back ends of load_mesh. Their failure messages are bare reasons; load_mesh prefixes the path.
#pragma once

#include "gust/gpu/result.hpp"
#include "gust/scene/mesh.hpp"

#include <cstddef>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace gust::detail {

/// A mesh file read into memory.
struct MeshFile {
    std::vector<unsigned char> bytes; ///< the whole file
    std::string extension;            ///< lower case, with the dot: ".glb"
    bool gltf() const { return extension == ".gltf" || extension == ".glb"; }
};

/// Reads the mesh file at `path` after the checks every format shares: it exists, is a regular file
/// with one of load_mesh's extensions, and is not empty.
Result<MeshFile> read_mesh_file(const std::filesystem::path& path);

/// Converts the PLY, OBJ or STL file held in `bytes` (whose extension, lower case without the dot, is
/// `extension`) with Assimp, after checking what Assimp would trust blindly (PLY and STL counts).
Result<Mesh> load_with_assimp(const std::vector<unsigned char>& bytes, std::string_view extension);

/// Converts the glTF or GLB file held in `bytes`; `path` locates external buffers next to it.
Result<Mesh> load_gltf(const std::vector<unsigned char>& bytes, const std::filesystem::path& path);

/// A third-party error message made fit for ours: one line of printable ASCII, at most about 300
/// characters (Assimp quotes whole stretches of the file in some messages).
std::string clean_message(std::string_view message);

/// Message for a result without triangles: "only points or lines" when `saw_points_or_lines`.
std::string no_triangles_reason(bool saw_points_or_lines);

} // namespace gust::detail
