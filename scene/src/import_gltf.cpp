// glTF 2.0 (.gltf and .glb) through tinygltf. tinygltf parses leniently: a property of the wrong JSON
// type is dropped without a word, a required extension it cannot decode surfaces as an unrelated
// error, and accessor ranges are not checked against their buffers. So the JSON is checked against
// the core schema's property types first (gltf_schema.cpp), and every accessor read is bounds-checked
// here.
#include "gltf_detail.hpp"
#include "import_detail.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <dlfcn.h>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <limits>
#include <map>
#include <span>
#include <string>
#include <string_view>
#include <tiny_gltf.h>
#include <vector>

namespace gust::detail {
namespace {

// Images are irrelevant to geometry; skipping their decoding saves time and a failure mode.
bool skip_image(tinygltf::Image*, const int, std::string*, std::string*, int, int, const unsigned char*, int,
                void*) {
    return true;
}

// ---------------------------------------------------------------------------------------------------
// Accessors

glm::vec3 decode_vec3(const unsigned char* p) {
    glm::vec3 v;
    std::memcpy(&v, p, sizeof v);
    return v;
}

Result<std::vector<glm::vec3>> read_positions(const tinygltf::Model& model, int index,
                                              std::size_t file_size) {
    const tinygltf::Accessor& accessor = model.accessors[static_cast<std::size_t>(index)];
    if (accessor.type != TINYGLTF_TYPE_VEC3 || accessor.componentType != TINYGLTF_COMPONENT_TYPE_FLOAT) {
        return Result<std::vector<glm::vec3>>::failure("POSITION accessor " + std::to_string(index) +
                                                       " is not float VEC3");
    }
    return read_accessor<glm::vec3>(model, index, file_size, decode_vec3);
}

Result<std::vector<std::uint32_t>> read_indices(const tinygltf::Model& model, int index,
                                                std::size_t file_size) {
    using R = Result<std::vector<std::uint32_t>>;
    if (index < 0 || static_cast<std::size_t>(index) >= model.accessors.size()) {
        return R::failure("indices accessor " + std::to_string(index) + " does not exist");
    }
    const tinygltf::Accessor& accessor = model.accessors[static_cast<std::size_t>(index)];
    if (accessor.type != TINYGLTF_TYPE_SCALAR) {
        return R::failure("indices accessor " + std::to_string(index) + " is not SCALAR");
    }
    switch (accessor.componentType) {
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
        return read_accessor<std::uint32_t>(model, index, file_size,
                                            [](const unsigned char* p) { return std::uint32_t{*p}; });
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT:
        return read_accessor<std::uint32_t>(model, index, file_size, [](const unsigned char* p) {
            std::uint16_t v;
            std::memcpy(&v, p, sizeof v);
            return std::uint32_t{v};
        });
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
        return read_accessor<std::uint32_t>(model, index, file_size, [](const unsigned char* p) {
            std::uint32_t v;
            std::memcpy(&v, p, sizeof v);
            return v;
        });
    default:
        return R::failure("indices accessor " + std::to_string(index) +
                          " is not unsigned byte, short or int");
    }
}

// ---------------------------------------------------------------------------------------------------
// Scene

class Builder {
  public:
    Builder(const tinygltf::Model& model, std::size_t file_size) : model_(model), file_size_(file_size) {}

    /// Adds the triangles of mesh `mesh_index` as instanced by node `node`, placed by `transform`.
    Status add_mesh(std::size_t mesh_index, const glm::dmat4& transform, int node) {
        const tinygltf::Mesh& mesh = model_.meshes[mesh_index];
        // Primitives often share one POSITION accessor (one primitive per material).
        std::map<int, std::uint32_t> bases;
        for (std::size_t p = 0; p < mesh.primitives.size(); ++p) {
            const tinygltf::Primitive& primitive = mesh.primitives[p];
            const int mode = primitive.mode < 0 ? TINYGLTF_MODE_TRIANGLES : primitive.mode;
            if (mode == TINYGLTF_MODE_POINTS || mode == TINYGLTF_MODE_LINE ||
                mode == TINYGLTF_MODE_LINE_LOOP || mode == TINYGLTF_MODE_LINE_STRIP) {
                saw_points_or_lines_ = true;
                continue;
            }
            if (mode != TINYGLTF_MODE_TRIANGLES && mode != TINYGLTF_MODE_TRIANGLE_STRIP &&
                mode != TINYGLTF_MODE_TRIANGLE_FAN) {
                return fail("unknown primitive mode " + std::to_string(mode), mesh_index, p);
            }
            if (Status status = add_primitive(primitive, mode, transform, bases, {node, mesh_index, p});
                !status) {
                return status;
            }
        }
        return {};
    }

    bool saw_points_or_lines() const { return saw_points_or_lines_; }
    Mesh& mesh() { return out_; }
    std::vector<GltfVertexBlock>& blocks() { return blocks_; }

  private:
    Status fail(const std::string& reason, std::size_t mesh, std::size_t primitive) const {
        return Status::failure(reason + " in " + primitive_name(model_, mesh, primitive));
    }

    Status add_primitive(const tinygltf::Primitive& primitive, int mode, const glm::dmat4& transform,
                         std::map<int, std::uint32_t>& bases, GltfVertexBlock block) {
        const std::size_t mesh = block.mesh;
        const std::size_t p = block.primitive;
        const auto position = primitive.attributes.find("POSITION");
        if (position == primitive.attributes.end()) return fail("no POSITION attribute", mesh, p);
        for (const auto& [name, accessor] : primitive.attributes) {
            if (accessor < 0 || static_cast<std::size_t>(accessor) >= model_.accessors.size()) {
                return fail(name + " accessor " + std::to_string(accessor) + " does not exist", mesh, p);
            }
        }
        const std::size_t vertices = model_.accessors[static_cast<std::size_t>(position->second)].count;
        for (const auto& [name, accessor] : primitive.attributes) {
            const std::size_t count = model_.accessors[static_cast<std::size_t>(accessor)].count;
            if (count != vertices) {
                return fail("accessor count mismatch: POSITION has " + std::to_string(vertices) +
                                " elements, " + name + " has " + std::to_string(count),
                            mesh, p);
            }
        }

        // Positions first: reading them checks the vertex count against the data actually present.
        auto base = bases.find(position->second);
        if (base == bases.end()) {
            Result<std::vector<glm::vec3>> positions = read_positions(model_, position->second, file_size_);
            if (!positions) return fail(positions.message(), mesh, p);
            if (out_.positions.size() + positions->size() > std::numeric_limits<std::uint32_t>::max()) {
                return Status::failure("too many vertices for 32-bit indices");
            }
            base = bases.emplace(position->second, static_cast<std::uint32_t>(out_.positions.size())).first;
            block.first = base->second;
            block.count = static_cast<std::uint32_t>(positions->size());
            blocks_.push_back(block);
            for (const glm::vec3& v : *positions) {
                out_.positions.emplace_back(transform * glm::dvec4(v, 1.0));
            }
        }

        std::vector<std::uint32_t> sequence;
        if (primitive.indices >= 0) {
            Result<std::vector<std::uint32_t>> indices = read_indices(model_, primitive.indices, file_size_);
            if (!indices) return fail(indices.message(), mesh, p);
            sequence = std::move(*indices);
            for (std::uint32_t index : sequence) {
                if (index >= vertices) {
                    return fail("index " + std::to_string(index) + " out of range (" +
                                    std::to_string(vertices) + " vertices)",
                                mesh, p);
                }
            }
        } else {
            sequence.resize(vertices);
            for (std::size_t i = 0; i < vertices; ++i) {
                sequence[i] = static_cast<std::uint32_t>(i);
            }
        }
        if (mode == TINYGLTF_MODE_TRIANGLES && sequence.size() % 3 != 0) {
            return fail(std::string(primitive.indices >= 0 ? "index" : "vertex") + " count " +
                            std::to_string(sequence.size()) + " is not a multiple of 3",
                        mesh, p);
        }
        append(sequence, mode, base->second);
        return {};
    }

    // Expands strips and fans to a triangle list with the winding the glTF specification gives.
    void append(const std::vector<std::uint32_t>& v, int mode, std::uint32_t base) {
        auto emit = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c) {
            out_.indices.insert(out_.indices.end(), {base + a, base + b, base + c});
        };
        if (mode == TINYGLTF_MODE_TRIANGLES) {
            for (std::size_t i = 0; i + 2 < v.size(); i += 3)
                emit(v[i], v[i + 1], v[i + 2]);
        } else if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
            for (std::size_t i = 0; i + 2 < v.size(); ++i) {
                if (i % 2 == 0) {
                    emit(v[i], v[i + 1], v[i + 2]);
                } else {
                    emit(v[i], v[i + 2], v[i + 1]);
                }
            }
        } else {
            for (std::size_t i = 1; i + 1 < v.size(); ++i)
                emit(v[i], v[i + 1], v[0]);
        }
    }

    const tinygltf::Model& model_;
    std::size_t file_size_;
    Mesh out_;
    std::vector<GltfVertexBlock> blocks_;
    bool saw_points_or_lines_ = false;
};

// Each node has at most one parent and the hierarchy has no cycle (both required by glTF); checked
// up front so that a cycle is reported as such rather than silently cut by the walk below.
Result<std::vector<int>> parents(const tinygltf::Model& model) {
    using R = Result<std::vector<int>>;
    const std::size_t n = model.nodes.size();
    std::vector<int> parent(n, -1);
    for (std::size_t i = 0; i < n; ++i) {
        for (int child : model.nodes[i].children) {
            if (child < 0 || static_cast<std::size_t>(child) >= n) {
                return R::failure("node " + std::to_string(i) + " has missing child " +
                                  std::to_string(child));
            }
            int& slot = parent[static_cast<std::size_t>(child)];
            if (slot != -1) {
                return R::failure("node " + std::to_string(child) + " has two parents (nodes " +
                                  std::to_string(slot) + " and " + std::to_string(i) + ")");
            }
            slot = static_cast<int>(i);
        }
    }
    enum : std::uint8_t { unseen, on_chain, done };
    std::vector<std::uint8_t> state(n, unseen);
    std::vector<int> chain;
    for (std::size_t start = 0; start < n; ++start) {
        chain.clear();
        int node = static_cast<int>(start);
        while (node != -1 && state[static_cast<std::size_t>(node)] == unseen) {
            state[static_cast<std::size_t>(node)] = on_chain;
            chain.push_back(node);
            node = parent[static_cast<std::size_t>(node)];
        }
        if (node != -1 && state[static_cast<std::size_t>(node)] == on_chain) {
            return R::failure("node cycle at node " + std::to_string(node));
        }
        for (int c : chain)
            state[static_cast<std::size_t>(c)] = done;
    }
    return parent;
}

Result<std::vector<int>> scene_roots(const tinygltf::Model& model, const std::vector<int>& parent) {
    using R = Result<std::vector<int>>;
    std::vector<int> roots;
    if (model.defaultScene < 0 && model.scenes.empty()) {
        for (std::size_t i = 0; i < parent.size(); ++i) {
            if (parent[i] == -1) roots.push_back(static_cast<int>(i));
        }
        return roots;
    }
    const std::size_t scene = model.defaultScene >= 0 ? static_cast<std::size_t>(model.defaultScene) : 0;
    if (scene >= model.scenes.size()) {
        return R::failure("scene " + std::to_string(scene) + " does not exist (the file has " +
                          std::to_string(model.scenes.size()) + " scenes)");
    }
    roots = model.scenes[scene].nodes;
    for (int root : roots) {
        if (root < 0 || static_cast<std::size_t>(root) >= parent.size()) {
            return R::failure("scene " + std::to_string(scene) + " lists missing node " +
                              std::to_string(root));
        }
    }
    return roots;
}

// libdraco, which Assimp links, exports its own tinygltf build under the same symbol names, and its
// types do not match this header. Calls go to whichever of the two the dynamic linker met first, so a
// link order with draco first would corrupt memory; refuse instead. tinygltf compiled into the same
// object as this code is fine too.
Status check_tinygltf_binding() {
    static const Status status = [] {
        Dl_info tinygltf_info{};
        Dl_info own_info{};
        if (dladdr(reinterpret_cast<void*>(&tinygltf::FileExists), &tinygltf_info) == 0 ||
            dladdr(reinterpret_cast<void*>(&check_tinygltf_binding), &own_info) == 0 ||
            tinygltf_info.dli_fname == nullptr || own_info.dli_fname == nullptr) {
            return Status{};
        }
        const std::string_view library = tinygltf_info.dli_fname;
        if (library.find("tinygltf") != std::string_view::npos || library == own_info.dli_fname)
            return Status{};
        return Status::failure("tinygltf calls resolve to " + std::string(library) +
                               " instead of libtinygltf; link TinyGLTF::TinyGLTF before assimp::assimp");
    }();
    return status;
}

/// tinygltf's own reader takes a folder for a buffer's file (its size reads as 2^63 and the allocation
/// threw) and would wait on a FIFO: a buffer or image the file names must be a regular file.
bool read_external_file(std::vector<unsigned char>* out, std::string* err, const std::string& path, void*) {
    std::error_code ec;
    const std::filesystem::file_status status = std::filesystem::status(path, ec);
    if (!std::filesystem::is_regular_file(status)) {
        if (err != nullptr) {
            *err += path + (std::filesystem::is_directory(status) ? " is a directory, not a file"
                            : std::filesystem::exists(status)     ? " is not a regular file"
                                                                  : " not found");
        }
        return false;
    }
    return tinygltf::ReadWholeFile(out, err, path, nullptr);
}

} // namespace

std::string primitive_name(const tinygltf::Model& model, std::size_t mesh, std::size_t primitive) {
    const std::string& name = model.meshes[mesh].name;
    return (name.empty() ? "mesh " + std::to_string(mesh) : "mesh '" + name + "'") + " primitive " +
           std::to_string(primitive);
}

Result<const unsigned char*> view_bytes(const tinygltf::Model& model, int view, std::uint64_t offset,
                                        std::uint64_t size, const std::string& what) {
    using R = Result<const unsigned char*>;
    if (view < 0 || static_cast<std::size_t>(view) >= model.bufferViews.size()) {
        return R::failure(what + " refers to missing buffer view " + std::to_string(view));
    }
    const tinygltf::BufferView& bv = model.bufferViews[static_cast<std::size_t>(view)];
    if (bv.buffer < 0 || static_cast<std::size_t>(bv.buffer) >= model.buffers.size()) {
        return R::failure("buffer view " + std::to_string(view) + " refers to missing buffer " +
                          std::to_string(bv.buffer));
    }
    const std::vector<unsigned char>& data = model.buffers[static_cast<std::size_t>(bv.buffer)].data;
    if (bv.byteOffset > data.size() || bv.byteLength > data.size() - bv.byteOffset) {
        return R::failure("buffer view " + std::to_string(view) + " lies outside its buffer (" +
                          std::to_string(data.size()) + " bytes)");
    }
    if (offset > bv.byteLength || size > bv.byteLength - offset) {
        return R::failure(what + " reads past the end of buffer view " + std::to_string(view));
    }
    return data.data() + bv.byteOffset + offset;
}

glm::dmat4 trs_matrix(const glm::dvec3& translation, glm::dquat rotation, const glm::dvec3& scale) {
    const double length = glm::length(rotation);
    if (length > 0) rotation /= length;
    return glm::scale(glm::translate(glm::dmat4(1.0), translation) * glm::mat4_cast(rotation), scale);
}

glm::dmat4 local_transform(const tinygltf::Node& node) {
    if (node.matrix.size() == 16) return glm::make_mat4(node.matrix.data());
    const std::vector<double>& t = node.translation;
    const std::vector<double>& r = node.rotation; // glTF order: x, y, z, w
    const std::vector<double>& s = node.scale;
    return trs_matrix(t.size() == 3 ? glm::make_vec3(t.data()) : glm::dvec3(0.0),
                      r.size() == 4 ? glm::dquat(r[3], r[0], r[1], r[2]) : glm::dquat(1.0, 0.0, 0.0, 0.0),
                      s.size() == 3 ? glm::make_vec3(s.data()) : glm::dvec3(1.0));
}

Result<tinygltf::Model> parse_gltf(const std::vector<unsigned char>& bytes,
                                   const std::filesystem::path& path) {
    using R = Result<tinygltf::Model>;
    if (bytes.size() > std::numeric_limits<unsigned int>::max()) {
        return R::failure("file too large for tinygltf (over 4 GiB)");
    }
    if (Status status = check_tinygltf_binding(); !status) return status;
    Result<std::string_view> text = json_text(bytes);
    if (!text) return text.status();
    if (Status status = check_json(*text); !status) return status;

    tinygltf::TinyGLTF loader;
    loader.SetImageLoader(skip_image, nullptr);
    loader.SetFsCallbacks({&tinygltf::FileExists, &tinygltf::ExpandFilePath, &read_external_file,
                           &tinygltf::WriteWholeFile, nullptr});
    tinygltf::Model model;
    std::string error;
    std::string warning;
    const std::string base_dir = path.parent_path().string();
    const auto size = static_cast<unsigned int>(bytes.size());
    bool loaded = false;
    try {
        loaded =
            is_glb(bytes)
                ? loader.LoadBinaryFromMemory(&model, &error, &warning, bytes.data(), size, base_dir)
                : loader.LoadASCIIFromString(&model, &error, &warning,
                                             reinterpret_cast<const char*>(bytes.data()), size, base_dir);
    } catch (const std::exception& e) {
        // tinygltf indexes some arrays with vector::at on values it has not checked.
        return R::failure("malformed glTF (tinygltf: " + clean_message(e.what()) + ")");
    }
    if (!loaded) return R::failure(error.empty() ? "tinygltf failed" : clean_message(error));
    return model;
}

Result<GltfGeometry> build_gltf(const tinygltf::Model& model, std::size_t file_size) {
    using R = Result<GltfGeometry>;
    Result<std::vector<int>> parent = parents(model);
    if (!parent) return parent.status();
    Result<std::vector<int>> roots = scene_roots(model, *parent);
    if (!roots) return roots.status();

    GltfGeometry geometry;
    geometry.walk_parent.assign(model.nodes.size(), -1);
    Builder builder(model, file_size);
    // Depth-first with an explicit stack: node chains can be as deep as the file is long.
    struct Visit {
        int node;
        int from;
        glm::dmat4 parent_world;
    };
    std::vector<Visit> stack;
    for (auto it = roots->rbegin(); it != roots->rend(); ++it)
        stack.push_back({*it, -1, glm::dmat4(1.0)});
    // Exporters do list non-root nodes as scene roots (Kenney's UniGLTF files list the child of a
    // "tmpParent" node), so such a node starts from the identity, and a node already reached through
    // another root is not instanced twice.
    std::vector<bool> visited(model.nodes.size(), false);
    while (!stack.empty()) {
        const Visit visit = stack.back();
        stack.pop_back();
        const auto index = static_cast<std::size_t>(visit.node);
        if (visited[index]) continue;
        visited[index] = true;
        geometry.walk_order.push_back(visit.node);
        geometry.walk_parent[index] = visit.from;
        const tinygltf::Node& node = model.nodes[index];
        const glm::dmat4 world = visit.parent_world * local_transform(node);
        if (node.mesh >= 0) {
            if (static_cast<std::size_t>(node.mesh) >= model.meshes.size()) {
                return R::failure("node " + std::to_string(visit.node) + " refers to missing mesh " +
                                  std::to_string(node.mesh));
            }
            // glTF ignores the node transform of a skinned mesh (the joints place it); with the
            // joints in their bind pose that leaves the raw POSITION data.
            const glm::dmat4 transform = node.skin >= 0 ? glm::dmat4(1.0) : world;
            if (Status status = builder.add_mesh(static_cast<std::size_t>(node.mesh), transform, visit.node);
                !status) {
                return status;
            }
        }
        for (auto it = node.children.rbegin(); it != node.children.rend(); ++it)
            stack.push_back({*it, visit.node, world});
    }
    if (builder.mesh().indices.empty()) return R::failure(no_triangles_reason(builder.saw_points_or_lines()));
    geometry.mesh = std::move(builder.mesh());
    geometry.blocks = std::move(builder.blocks());
    geometry.parent = std::move(*parent);
    return geometry;
}

Result<Mesh> load_gltf(const std::vector<unsigned char>& bytes, const std::filesystem::path& path) {
    Result<tinygltf::Model> model = parse_gltf(bytes, path);
    if (!model) return model.status();
    return gltf_rest_pose(*model, bytes.size());
}

} // namespace gust::detail
