// PLY, OBJ and STL through Assimp. Assimp sizes its allocations from the counts in a PLY header without
// comparing them with the file size (a PLY declaring 3.5e11 faces makes it allocate until the machine
// runs out of memory) and checks a binary STL's triangle count in 32-bit arithmetic, so those counts are
// checked here first.
#include "import_detail.hpp"

#include <array>
#include <assimp/Importer.hpp>
#include <assimp/config.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

namespace gust::detail {
namespace {

// ---------------------------------------------------------------------------------------------------
// PLY structure check

struct PlyType {
    std::string_view name;
    std::size_t size;
    bool is_signed;
    bool is_float;
};

constexpr PlyType kPlyTypes[] = {
    {"char", 1, true, false},    {"int8", 1, true, false},    {"uchar", 1, false, false},
    {"uint8", 1, false, false},  {"short", 2, true, false},   {"int16", 2, true, false},
    {"ushort", 2, false, false}, {"uint16", 2, false, false}, {"int", 4, true, false},
    {"int32", 4, true, false},   {"uint", 4, false, false},   {"uint32", 4, false, false},
    {"float", 4, true, true},    {"float32", 4, true, true},  {"double", 8, true, true},
    {"float64", 8, true, true},
};

const PlyType* find_ply_type(std::string_view name) {
    for (const PlyType& type : kPlyTypes) {
        if (type.name == name) return &type;
    }
    return nullptr;
}

struct PlyProperty {
    const PlyType* count = nullptr; ///< list length type; null for a scalar property
    const PlyType* value = nullptr;
};

struct PlyElement {
    std::string name;
    std::uint64_t count = 0;
    std::vector<PlyProperty> properties;
};

enum class PlyFormat { ascii, little_endian, big_endian };

struct PlyHeader {
    PlyFormat format = PlyFormat::ascii;
    std::vector<PlyElement> elements;
    std::size_t data_offset = 0; ///< first byte after "end_header\n"
};

std::vector<std::string_view> split(std::string_view line) {
    std::vector<std::string_view> words;
    std::size_t i = 0;
    while (i < line.size()) {
        while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) {
            ++i;
        }
        const std::size_t start = i;
        while (i < line.size() && line[i] != ' ' && line[i] != '\t') {
            ++i;
        }
        if (i > start) words.push_back(line.substr(start, i - start));
    }
    return words;
}

std::optional<std::uint64_t> parse_count(std::string_view text) {
    std::uint64_t value = 0;
    const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
    if (ec != std::errc() || end != text.data() + text.size()) return std::nullopt;
    return value;
}

Result<PlyHeader> parse_ply_header(std::string_view text) {
    using R = Result<PlyHeader>;
    PlyHeader header;
    bool have_format = false;
    std::size_t pos = 0;
    for (int line_number = 1;; ++line_number) {
        const std::size_t eol = text.find('\n', pos);
        if (eol == std::string_view::npos) return R::failure("PLY header has no end_header line");
        std::string_view line = text.substr(pos, eol - pos);
        pos = eol + 1;
        if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
        const std::vector<std::string_view> words = split(line);
        const std::string where = " (PLY header line " + std::to_string(line_number) + ")";
        if (line_number == 1) {
            if (line != "ply") return R::failure("not a PLY file (first line is not 'ply')");
            continue;
        }
        if (words.empty() || words[0] == "comment" || words[0] == "obj_info") continue;
        if (words[0] == "end_header") break;
        if (words[0] == "format") {
            if (words.size() != 3) return R::failure("malformed format line" + where);
            if (words[1] == "ascii") {
                header.format = PlyFormat::ascii;
            } else if (words[1] == "binary_little_endian") {
                header.format = PlyFormat::little_endian;
            } else if (words[1] == "binary_big_endian") {
                header.format = PlyFormat::big_endian;
            } else {
                return R::failure("unknown PLY format '" + std::string(words[1]) + "'" + where);
            }
            have_format = true;
        } else if (words[0] == "element") {
            if (words.size() != 3) return R::failure("malformed element line" + where);
            const std::optional<std::uint64_t> count = parse_count(words[2]);
            if (!count) return R::failure("bad element count '" + std::string(words[2]) + "'" + where);
            header.elements.push_back({std::string(words[1]), *count, {}});
        } else if (words[0] == "property") {
            if (header.elements.empty()) return R::failure("property before any element" + where);
            PlyProperty property;
            const bool is_list = words.size() >= 2 && words[1] == "list";
            if (words.size() != (is_list ? 5u : 3u)) return R::failure("malformed property line" + where);
            const std::string_view type_name = is_list ? words[3] : words[1];
            property.value = find_ply_type(type_name);
            if (!property.value) {
                return R::failure("unknown PLY type '" + std::string(type_name) + "'" + where);
            }
            if (is_list) {
                property.count = find_ply_type(words[2]);
                if (!property.count || property.count->is_float) {
                    return R::failure("list length type '" + std::string(words[2]) +
                                      "' is not an integer type" + where);
                }
            }
            header.elements.back().properties.push_back(property);
        }
        // Other keywords are skipped, as Assimp does.
    }
    if (!have_format) return R::failure("PLY header has no format line");
    header.data_offset = pos;
    return header;
}

// Decodes a binary list length; nullopt when it is negative.
std::optional<std::uint64_t> binary_count(const unsigned char* p, const PlyType& type, bool big_endian) {
    std::uint64_t value = 0;
    for (std::size_t i = 0; i < type.size; ++i) {
        value |= std::uint64_t{p[big_endian ? type.size - 1 - i : i]} << (8 * i);
    }
    if (type.is_signed && ((value >> (8 * type.size - 1)) & 1u)) return std::nullopt;
    return value;
}

std::string truncated(const PlyElement& element, std::uint64_t item) {
    return "file truncated: data ends inside element '" + element.name + "' " + std::to_string(item) +
           " of " + std::to_string(element.count);
}

// Walks the binary payload the way a reader would, without storing anything.
Status check_ply_binary(const PlyHeader& header, std::span<const unsigned char> data) {
    const bool big_endian = header.format == PlyFormat::big_endian;
    std::size_t pos = 0;
    for (const PlyElement& element : header.elements) {
        for (std::uint64_t item = 0; item < element.count; ++item) {
            for (const PlyProperty& property : element.properties) {
                std::uint64_t bytes = property.value->size;
                if (property.count) {
                    if (data.size() - pos < property.count->size) {
                        return Status::failure(truncated(element, item));
                    }
                    const std::optional<std::uint64_t> length =
                        binary_count(data.data() + pos, *property.count, big_endian);
                    if (!length) {
                        return Status::failure("negative list length in element '" + element.name + "' " +
                                               std::to_string(item));
                    }
                    pos += property.count->size;
                    if (*length > (data.size() - pos) / property.value->size) {
                        return Status::failure(truncated(element, item));
                    }
                    bytes = *length * property.value->size;
                }
                if (data.size() - pos < bytes) return Status::failure(truncated(element, item));
                pos += static_cast<std::size_t>(bytes);
            }
        }
    }
    return {};
}

bool is_space(unsigned char c) {
    return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f' || c == '\v';
}

// Walks the ASCII payload token by token, checking list lengths, without storing anything.
Status check_ply_ascii(const PlyHeader& header, std::span<const unsigned char> data) {
    std::size_t pos = 0;
    auto next_token = [&]() -> std::optional<std::string_view> {
        while (pos < data.size() && is_space(data[pos])) {
            ++pos;
        }
        const std::size_t start = pos;
        while (pos < data.size() && !is_space(data[pos])) {
            ++pos;
        }
        if (pos == start) return std::nullopt;
        return std::string_view(reinterpret_cast<const char*>(data.data()) + start, pos - start);
    };
    for (const PlyElement& element : header.elements) {
        for (std::uint64_t item = 0; item < element.count; ++item) {
            for (const PlyProperty& property : element.properties) {
                const std::optional<std::string_view> token = next_token();
                if (!token) return Status::failure(truncated(element, item));
                if (!property.count) continue;
                const std::optional<std::uint64_t> length = parse_count(*token);
                if (!length) {
                    return Status::failure("bad list length '" + std::string(*token) + "' in element '" +
                                           element.name + "' " + std::to_string(item));
                }
                for (std::uint64_t k = 0; k < *length; ++k) {
                    if (!next_token()) return Status::failure(truncated(element, item));
                }
            }
        }
    }
    return {};
}

Status check_ply(const std::vector<unsigned char>& bytes) {
    const std::string_view text(reinterpret_cast<const char*>(bytes.data()), bytes.size());
    Result<PlyHeader> header = parse_ply_header(text);
    if (!header) return header.status();
    const std::span<const unsigned char> data(bytes.data() + header->data_offset,
                                              bytes.size() - header->data_offset);

    // A header count that cannot fit in the file is reported as such before any walking.
    std::uint64_t needed = 0;
    for (const PlyElement& element : header->elements) {
        if (element.count == 0) continue;
        if (element.properties.empty()) {
            return Status::failure("element '" + element.name + "' has " + std::to_string(element.count) +
                                   " items but no properties");
        }
        std::uint64_t min_item = 0; // smallest possible encoding of one item
        for (const PlyProperty& property : element.properties) {
            if (header->format == PlyFormat::ascii) {
                min_item += 1; // at least one character per value
            } else {
                min_item += property.count ? property.count->size : property.value->size;
            }
        }
        if (element.count > (data.size() - needed) / min_item) {
            return Status::failure("header declares " + std::to_string(element.count) + " '" + element.name +
                                   "' items, more than the " + std::to_string(data.size()) +
                                   " bytes of data can hold");
        }
        needed += element.count * min_item;
    }
    return header->format == PlyFormat::ascii ? check_ply_ascii(*header, data)
                                              : check_ply_binary(*header, data);
}

// ---------------------------------------------------------------------------------------------------
// STL check

// Mirrors Assimp's choice between ASCII and binary STL, then checks the binary triangle count.
Status check_stl(const std::vector<unsigned char>& bytes) {
    constexpr std::uint64_t kHeader = 84; // 80-byte comment + uint32 triangle count
    constexpr std::uint64_t kTriangle = 50;
    const std::uint64_t size = bytes.size();
    std::uint64_t count = 0;
    if (size >= kHeader) {
        for (std::size_t i = 0; i < 4; ++i) {
            count |= std::uint64_t{bytes[80 + i]} << (8 * i);
        }
        if (kHeader + kTriangle * count == size) return {};
        // Assimp computes the expected size in 32 bits; a count that only matches after wrapping would
        // make it read the file as binary and allocate for the full count.
        if (static_cast<std::uint32_t>(kHeader + kTriangle * count) == static_cast<std::uint32_t>(size)) {
            return Status::failure("corrupt binary STL header (triangle count " + std::to_string(count) +
                                   ")");
        }
    }
    std::size_t start = 0; // Assimp skips blanks, not line ends, before looking for "solid"
    while (start < bytes.size() && (bytes[start] == ' ' || bytes[start] == '\t')) {
        ++start;
    }
    const std::string_view text(reinterpret_cast<const char*>(bytes.data()) + start, bytes.size() - start);
    if (text.starts_with("solid")) return {};
    if (size < kHeader) {
        return Status::failure("not an STL file (too small for a binary STL header and not ASCII STL)");
    }
    if (kHeader + kTriangle * count > size) {
        return Status::failure("file truncated: binary STL header declares " + std::to_string(count) +
                               " triangles (" + std::to_string(kHeader + kTriangle * count) +
                               " bytes) but the file has " + std::to_string(size) + " bytes");
    }
    return {};
}

// ---------------------------------------------------------------------------------------------------
// Assimp

// Counts faces on the scene as the format reader produced it, before any post-processing.
struct FaceCounts {
    std::size_t polygons = 0; ///< faces with three or more corners
    std::size_t other = 0;    ///< points and lines
};

FaceCounts count_faces(const aiScene& scene) {
    FaceCounts counts;
    if (!scene.mMeshes) return counts;
    for (unsigned m = 0; m < scene.mNumMeshes; ++m) {
        const aiMesh* mesh = scene.mMeshes[m];
        if (!mesh) continue;
        if (mesh->mNumFaces == 0 || !mesh->mFaces) {
            counts.other += mesh->mNumVertices > 0 ? 1 : 0; // a point cloud
            continue;
        }
        for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
            (mesh->mFaces[f].mNumIndices >= 3 ? counts.polygons : counts.other) += 1;
        }
    }
    return counts;
}

/// Merges vertices at exactly the same position, keeping the first's index, so that files listing each
/// triangle's corners apart (STL, many PLYs) share them. Non-finite positions are never merged: Assimp's
/// JoinIdenticalVertices compared positions with `<`, so a NaN corner compared equal to a finite one and
/// was merged into it, and its triangle became a finite zero-area one (skipped) instead of a rejected one.
class Welder {
  public:
    explicit Welder(Mesh& mesh) : mesh_(mesh) {}
    std::uint32_t add(const aiVector3D& p) {
        const glm::vec3 position(p.x, p.y, p.z);
        const bool finite = std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
        if (finite) {
            // +0.0 and −0.0 are one position.
            const Key key{std::bit_cast<std::uint32_t>(p.x + 0.0f), std::bit_cast<std::uint32_t>(p.y + 0.0f),
                          std::bit_cast<std::uint32_t>(p.z + 0.0f)};
            const auto [at, added] = seen_.try_emplace(key, std::uint32_t(mesh_.positions.size()));
            if (!added) return at->second;
        }
        mesh_.positions.push_back(position);
        return std::uint32_t(mesh_.positions.size() - 1);
    }

  private:
    using Key = std::array<std::uint32_t, 3>;
    struct Hash {
        std::size_t operator()(const Key& k) const {
            return std::hash<std::uint64_t>{}((std::uint64_t(k[0]) << 32 | k[1]) ^
                                              (std::uint64_t(k[2]) * 0x9e3779b97f4a7c15ull));
        }
    };
    Mesh& mesh_;
    std::unordered_map<Key, std::uint32_t, Hash> seen_;
};

} // namespace

Result<Mesh> load_with_assimp(const std::vector<unsigned char>& bytes, std::string_view extension) {
    if (extension == "ply") {
        if (Status status = check_ply(bytes); !status) return status;
    } else if (extension == "stl") {
        if (Status status = check_stl(bytes); !status) return status;
    }

    Assimp::Importer importer;
    // Only positions matter.
    importer.SetPropertyInteger(AI_CONFIG_PP_RVC_FLAGS,
                                aiComponent_NORMALS | aiComponent_TANGENTS_AND_BITANGENTS |
                                    aiComponent_COLORS | aiComponent_TEXCOORDS | aiComponent_BONEWEIGHTS |
                                    aiComponent_ANIMATIONS | aiComponent_TEXTURES | aiComponent_LIGHTS |
                                    aiComponent_CAMERAS | aiComponent_MATERIALS);
    const std::string hint(extension);
    // Read without post-processing first: Assimp's validation rejects point clouds ("contains no faces")
    // with a message that hides the actual reason, so the face kinds are counted on the raw scene.
    const aiScene* raw = importer.ReadFileFromMemory(bytes.data(), bytes.size(), 0, hint.c_str());
    if (!raw) return Result<Mesh>::failure("cannot parse: " + clean_message(importer.GetErrorString()));
    const FaceCounts counts = count_faces(*raw);
    if (counts.polygons == 0) return Result<Mesh>::failure(no_triangles_reason(counts.other > 0));

    const aiScene* scene =
        importer.ApplyPostProcessing(aiProcess_ValidateDataStructure | aiProcess_RemoveComponent |
                                     aiProcess_Triangulate | aiProcess_PreTransformVertices);
    if (!scene) {
        return Result<Mesh>::failure("invalid mesh data: " + clean_message(importer.GetErrorString()));
    }

    Mesh mesh;
    Welder welder(mesh);
    std::vector<std::uint32_t> index;
    for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
        const aiMesh& in = *scene->mMeshes[m];
        if (mesh.positions.size() + in.mNumVertices > std::numeric_limits<std::uint32_t>::max()) {
            return Result<Mesh>::failure("too many vertices for 32-bit indices");
        }
        index.resize(in.mNumVertices);
        for (unsigned v = 0; v < in.mNumVertices; ++v)
            index[v] = welder.add(in.mVertices[v]);
        for (unsigned f = 0; f < in.mNumFaces; ++f) {
            const aiFace& face = in.mFaces[f];
            if (face.mNumIndices != 3) continue; // points and lines left by Triangulate
            mesh.indices.insert(mesh.indices.end(),
                                {index[face.mIndices[0]], index[face.mIndices[1]], index[face.mIndices[2]]});
        }
    }
    if (mesh.indices.empty()) return Result<Mesh>::failure(no_triangles_reason(true));
    return mesh;
}

} // namespace gust::detail
