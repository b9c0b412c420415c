#include "gust/scene/import.hpp"

#include "import_detail.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <cstdint>
#include <fstream>
#include <limits>
#include <new>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

namespace gust {
namespace {

namespace fs = std::filesystem;

constexpr std::array<std::string_view, 5> kExtensions = {".ply", ".obj", ".stl", ".gltf", ".glb"};

std::string lower(std::string text) {
    std::transform(text.begin(), text.end(), text.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return text;
}

std::string expected_extensions() {
    std::string list;
    for (std::string_view ext : kExtensions) {
        list += list.empty() ? "" : ", ";
        list += ext;
    }
    return "(expected " + list + ")";
}

// Reads the whole file: every back end needs it in memory, and reading it once means the checks made
// on the bytes hold for what the parser sees.
Result<std::vector<unsigned char>> read_bytes(const fs::path& path, std::uintmax_t size) {
    std::ifstream in(path, std::ios::binary);
    if (!in) return Result<std::vector<unsigned char>>::failure("cannot open file for reading");
    std::vector<unsigned char> bytes(static_cast<std::size_t>(size));
    in.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
    if (static_cast<std::size_t>(in.gcount()) != bytes.size()) {
        return Result<std::vector<unsigned char>>::failure("cannot read file (read " +
                                                           std::to_string(in.gcount()) + " of " +
                                                           std::to_string(size) + " bytes)");
    }
    return bytes;
}

// Empty when `mesh` is a whole triangle list with every index in range; the reason otherwise.
std::string problem(const Mesh& mesh) {
    if (mesh.indices.size() % 3 != 0) {
        return "index count " + std::to_string(mesh.indices.size()) + " is not a multiple of 3";
    }
    const std::size_t vertices = mesh.positions.size();
    for (std::size_t i = 0; i < mesh.indices.size(); ++i) {
        if (mesh.indices[i] >= vertices) {
            return "index " + std::to_string(mesh.indices[i]) + " out of range (" + std::to_string(vertices) +
                   " vertices) at triangle " + std::to_string(i / 3);
        }
    }
    return {};
}

Result<Mesh> load(const fs::path& path) {
    Result<detail::MeshFile> file = detail::read_mesh_file(path);
    if (!file) return file.status();
    const std::vector<unsigned char>& bytes = file->bytes;
    Result<Mesh> mesh = file->gltf() ? detail::load_gltf(bytes, path)
                                     : detail::load_with_assimp(bytes, file->extension.substr(1));
    if (!mesh) return mesh;
    if (std::string reason = problem(*mesh); !reason.empty()) return Result<Mesh>::failure(reason);
    mesh->name = path.filename().string();
    return mesh;
}

} // namespace

Result<Mesh> load_mesh(const std::filesystem::path& path) {
    std::string reason;
    try {
        Result<Mesh> mesh = load(path);
        if (mesh) return mesh;
        reason = mesh.message();
    } catch (const std::bad_alloc&) {
        reason = "out of memory";
    } catch (const std::exception& e) {
        reason = "unexpected error: " + detail::clean_message(e.what());
    }
    return Result<Mesh>::failure(path.string() + ": " + reason);
}

Status validate_mesh(const Mesh& mesh) {
    std::string reason = problem(mesh);
    if (reason.empty()) return {};
    return Status::failure((mesh.name.empty() ? std::string("mesh") : mesh.name) + ": " + reason);
}

namespace detail {

Result<MeshFile> read_mesh_file(const std::filesystem::path& path) {
    std::error_code ec;
    const fs::file_status status = fs::status(path, ec);
    if (!fs::exists(status)) {
        if (ec && ec != std::errc::no_such_file_or_directory) {
            return Result<MeshFile>::failure("cannot access file (" + ec.message() + ")");
        }
        return Result<MeshFile>::failure("file not found");
    }
    if (fs::is_directory(status)) return Result<MeshFile>::failure("is a directory, not a mesh file");
    if (!fs::is_regular_file(status)) return Result<MeshFile>::failure("not a regular file");

    MeshFile file;
    file.extension = lower(path.extension().string());
    if (std::find(kExtensions.begin(), kExtensions.end(), file.extension) == kExtensions.end()) {
        const std::string what =
            file.extension.empty() ? "no file extension" : "unsupported extension '" + file.extension + "'";
        return Result<MeshFile>::failure(what + " " + expected_extensions());
    }

    const std::uintmax_t size = fs::file_size(path, ec);
    if (ec) return Result<MeshFile>::failure("cannot read file size (" + ec.message() + ")");
    if (size == 0) return Result<MeshFile>::failure("empty file");
    if (size > std::numeric_limits<std::size_t>::max()) return Result<MeshFile>::failure("file too large");

    Result<std::vector<unsigned char>> bytes = read_bytes(path, size);
    if (!bytes) return bytes.status();
    file.bytes = std::move(*bytes);
    return file;
}

std::string clean_message(std::string_view message) {
    constexpr std::size_t kMaxLength = 300;
    // Assimp names a file read from memory "$$$___magic___$$$.<ext>".
    constexpr std::string_view kMemoryFile = "$$$___magic___$$$";
    std::string out;
    for (std::size_t i = 0; i < message.size() && out.size() < kMaxLength; ++i) {
        if (message.substr(i).starts_with(kMemoryFile)) {
            out += "file";
            i += kMemoryFile.size() - 1;
            continue;
        }
        const auto c = static_cast<unsigned char>(message[i]);
        if (c == '\n' || c == '\r') {
            if (!out.empty() && !out.ends_with("; ")) out += "; ";
        } else {
            out += (c >= 0x20 && c < 0x7f) ? static_cast<char>(c) : '?';
        }
    }
    while (out.ends_with("; ") || out.ends_with(' ')) {
        out.pop_back();
    }
    if (out.size() >= kMaxLength) out += "...";
    return out;
}

std::string no_triangles_reason(bool saw_points_or_lines) {
    return saw_points_or_lines ? "no triangles (only points or lines)" : "no triangles (no mesh geometry)";
}

} // namespace detail
} // namespace gust
