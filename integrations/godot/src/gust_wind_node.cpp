// GustWind: a Spatial that owns one gust System centred on itself. Every physics frame it reports the
// MeshInstances of its obstacle group and its GustEmitter children, steps, and publishes the field as a
// Texture3D to the ShaderMaterials of its material group (docs/godot.md).
#include "nodes.hpp"
#include "wind_host.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <iterator>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <shared_mutex>

namespace gust::godot {

namespace {

constexpr char kClass[] = "GustWind";
const int kTypeTag = 0;                           // its address tags GustWind instances
constexpr std::int64_t kImageFormatRgbaf = 11;    // Image.FORMAT_RGBAF
constexpr std::int64_t kTextureFlagFilter = 4;    // Texture3D.FLAG_FILTER: linear, clamped to the edge
constexpr std::int64_t kPrimitiveTriangles = 4;   // Mesh.PRIMITIVE_TRIANGLES
constexpr std::int64_t kArrayVertex = 0;          // Mesh.ARRAY_VERTEX
constexpr std::int64_t kArrayBones = 6;           // Mesh.ARRAY_BONES: 4 bone (bind) indices a vertex
constexpr std::int64_t kArrayWeights = 7;         // Mesh.ARRAY_WEIGHTS: 4 weights a vertex
constexpr std::int64_t kArrayIndex = 8;           // Mesh.ARRAY_INDEX
constexpr std::int64_t kArrayFormatBones = 64;    // Mesh.ARRAY_FORMAT_BONES
constexpr std::int64_t kArrayFormatWeights = 128; // Mesh.ARRAY_FORMAT_WEIGHTS

// A skinned obstacle's gust mesh and what it was made from (a change of any uploads it again).
struct Skinned {
    std::uint64_t mesh = 0, skin = 0, skeleton = 0; // instance ids; skin 0: Godot's default skin
    std::size_t joints = 0;
    std::uint64_t key = 0; // WindHost mesh key
    bool refused = false;  // gust refused it: taken in its rest pose
    bool seen = false;
};

// What the readers share with the node: the host, whose System answers sample() from any thread, and the
// ambient wind answered before the first step. A GustSampler holds it too, so it outlives a freed node (whose
// System is destroyed first: a sampler then answers the ambient wind).
struct Shared {
    // Readers hold it shared; recreating or destroying the System holds it exclusively.
    std::shared_mutex mutex;
    integration::WindHost host;
    Vec3 ambient{};
};

struct Wind {
    godot_object* owner = nullptr;
    integration::WindHostConfig config;
    std::string obstacle_group = "gust_obstacles";
    std::string material_group = "gust_wind_materials";
    bool auto_step = true;
    bool dirty = true; // the System is (re)created at the next step
    std::shared_ptr<Shared> shared = std::make_shared<Shared>();
    integration::WindHost& host = shared->host;
    std::set<std::uint64_t> reported;         // nodes and meshes already logged about, once each
    std::map<std::uint64_t, Skinned> skinned; // by MeshInstance
    // Skinned meshes are per node: their keys have the top bit set, apart from Godot's instance ids
    // (Meshes').
    std::uint64_t next_skinned_key = std::uint64_t(1) << 63;
    std::string last_error;
    Var texture;
    std::uint32_t texture_extent[3] = {};
    integration::WindField field;
    godot_transform world_to_texture{};
    double publish_ms = 0.0;
};

Wind& self(void* user) {
    return *static_cast<Wind*>(user);
}

void report(Wind& w, const std::string& message) {
    if (message != w.last_error) {
        error(message, "GustWind");
    }
    w.last_error = message;
}

void report_once(Wind& w, std::uint64_t key, const std::string& message) {
    if (w.reported.insert(key).second) {
        error(message, "GustWind");
    }
}

// Sets a property through a copy of the config that must validate; otherwise logs and keeps the old value.
template <class F> void set_config(Wind& w, F change) {
    integration::WindHostConfig next = w.config;
    change(next);
    next.focus = w.config.focus;
    if (std::string message = integration::validate(next); !message.empty()) {
        error("GustWind." + message + " (the previous value is kept)", "GustWind");
        return;
    }
    std::unique_lock lock(w.shared->mutex);
    w.config = next;
    w.dirty = true;
}

std::uint32_t to_cells(double v) {
    return std::isfinite(v) && v >= 0.0 && v < 1e6 ? std::uint32_t(v) : 0u;
}

void set_cells(godot_object*, void*, void* u, godot_variant* v) {
    const Float3 c = to_float3(core->godot_variant_as_vector3(v));
    if (c.x != std::floor(c.x) || c.y != std::floor(c.y) || c.z != std::floor(c.z)) {
        error("GustWind.cells must be whole numbers of cells (the previous value is kept)", "GustWind");
        return;
    }
    set_config(self(u), [&](integration::WindHostConfig& n) {
        n.cells[0] = to_cells(c.x);
        n.cells[1] = to_cells(c.y);
        n.cells[2] = to_cells(c.z);
    });
}
void set_cell_size(godot_object*, void*, void* u, godot_variant* v) {
    const double s = core->godot_variant_as_real(v);
    set_config(self(u), [&](integration::WindHostConfig& n) { n.cell_size = float(s); });
}
void set_voxels(godot_object*, void*, void* u, godot_variant* v) {
    const std::int64_t n = core->godot_variant_as_int(v);
    set_config(self(u), [&](integration::WindHostConfig& c) {
        c.voxels_per_cell = n < 0 || n > 1000 ? 0u : std::uint32_t(n);
    });
}
void set_quality(godot_object*, void*, void* u, godot_variant* v) {
    const std::int64_t q = core->godot_variant_as_int(v);
    set_config(self(u), [&](integration::WindHostConfig& c) {
        c.quality = q < -1000 || q > 1000 ? -1 : std::int32_t(q);
    });
}
void set_ambient(godot_object*, void*, void* u, godot_variant* v) {
    Wind& w = self(u);
    const Float3 a = to_float3(core->godot_variant_as_vector3(v));
    integration::WindHostConfig next = w.config;
    next.ambient = {a.x, a.y, a.z};
    if (std::string message = integration::validate(next); !message.empty()) {
        error("GustWind." + message + " (the previous value is kept)", "GustWind");
        return;
    }
    {
        // Readers answer the ambient wind before the first step: they read it under the lock.
        std::unique_lock lock(w.shared->mutex);
        w.config.ambient = next.ambient;
        w.shared->ambient = next.ambient;
    }
    if (Outcome o = w.host.set_ambient(next.ambient); !o) {
        report(w, o.message());
    }
}
std::string as_string(const godot_variant* v) {
    godot_variant copy;
    core->godot_variant_new_copy(&copy, v);
    return Var(copy).as_string();
}
void set_obstacle_group(godot_object*, void*, void* u, godot_variant* v) {
    self(u).obstacle_group = as_string(v);
}
void set_material_group(godot_object*, void*, void* u, godot_variant* v) {
    self(u).material_group = as_string(v);
}
void set_auto_step(godot_object*, void*, void* u, godot_variant* v) {
    self(u).auto_step = core->godot_variant_as_bool(v);
}

godot_variant get_cells(godot_object*, void*, void* u) {
    const auto& c = self(u).config.cells;
    return Var(to_vector3(float(c[0]), float(c[1]), float(c[2]))).release();
}
godot_variant get_cell_size(godot_object*, void*, void* u) {
    return Var(double(self(u).config.cell_size)).release();
}
godot_variant get_voxels(godot_object*, void*, void* u) {
    return Var(std::int64_t(self(u).config.voxels_per_cell)).release();
}
godot_variant get_quality(godot_object*, void*, void* u) {
    return Var(std::int64_t(self(u).config.quality)).release();
}
godot_variant get_ambient(godot_object*, void*, void* u) {
    const Vec3& a = self(u).config.ambient;
    return Var(to_vector3(a.x, a.y, a.z)).release();
}
godot_variant get_obstacle_group(godot_object*, void*, void* u) {
    return Var(self(u).obstacle_group.c_str()).release();
}
godot_variant get_material_group(godot_object*, void*, void* u) {
    return Var(self(u).material_group.c_str()).release();
}
godot_variant get_auto_step(godot_object*, void*, void* u) {
    return Var(self(u).auto_step).release();
}

// Appends a PoolIntArray's or PoolRealArray's numbers to `out`; false for any other Variant.
template <class T> bool append_numbers(const Var& v, std::vector<T>& out) {
    if (v.type() == GODOT_VARIANT_TYPE_POOL_INT_ARRAY) {
        godot_pool_int_array a = core->godot_variant_as_pool_int_array(v.get());
        const godot_int n = core->godot_pool_int_array_size(&a);
        godot_pool_int_array_read_access* r = core->godot_pool_int_array_read(&a);
        const godot_int* p = core->godot_pool_int_array_read_access_ptr(r);
        out.insert(out.end(), p, p + n);
        core->godot_pool_int_array_read_access_destroy(r);
        core->godot_pool_int_array_destroy(&a);
        return true;
    }
    if (v.type() == GODOT_VARIANT_TYPE_POOL_REAL_ARRAY) {
        godot_pool_real_array a = core->godot_variant_as_pool_real_array(v.get());
        const godot_int n = core->godot_pool_real_array_size(&a);
        godot_pool_real_array_read_access* r = core->godot_pool_real_array_read(&a);
        const godot_real* p = core->godot_pool_real_array_read_access_ptr(r);
        for (godot_int i = 0; i < n; ++i) {
            out.push_back(T(p[i]));
        }
        core->godot_pool_real_array_read_access_destroy(r);
        core->godot_pool_real_array_destroy(&a);
        return true;
    }
    return false;
}

// A Mesh's triangles in mesh space, every triangle surface in one list; with `skinned`, also each vertex's 4
// bone indices and weights (Godot 3's ARRAY_BONES and ARRAY_WEIGHTS).
struct MeshArrays {
    std::vector<float> positions;
    std::vector<std::uint32_t> indices;
    std::vector<std::int32_t> joints;
    std::vector<float> weights;
};

// Fills `out` from `mesh`; false with the reason in `why` when it has no triangles or (skinned) a triangle
// surface lacks 4 bone indices and weights a vertex.
bool read_mesh(godot_object* mesh, bool skinned, MeshArrays& out, std::string& why) {
    const std::int64_t surfaces = call(mesh, "Mesh", "get_surface_count").as_int();
    for (std::int64_t s = 0; s < surfaces; ++s) {
        Var index(s);
        // Only an ArrayMesh may hold lines or points; a PrimitiveMesh (CubeMesh, PlaneMesh...) is triangles.
        if (is_class(mesh, "ArrayMesh") &&
            call(mesh, "ArrayMesh", "surface_get_primitive_type", {&index}).as_int() != kPrimitiveTriangles) {
            continue;
        }
        std::vector<Var> arrays = array_items(call(mesh, "Mesh", "surface_get_arrays", {&index}));
        if (arrays.size() <= std::size_t(kArrayIndex) ||
            arrays[kArrayVertex].type() != GODOT_VARIANT_TYPE_POOL_VECTOR3_ARRAY) {
            continue;
        }
        const auto base = std::uint32_t(out.positions.size() / 3);
        godot_pool_vector3_array verts =
            core->godot_variant_as_pool_vector3_array(arrays[kArrayVertex].get());
        const godot_int nv = core->godot_pool_vector3_array_size(&verts);
        godot_pool_vector3_array_read_access* vr = core->godot_pool_vector3_array_read(&verts);
        const godot_vector3* vp = core->godot_pool_vector3_array_read_access_ptr(vr);
        for (godot_int i = 0; i < nv; ++i) {
            const Float3 p = to_float3(vp[i]);
            out.positions.insert(out.positions.end(), {p.x, p.y, p.z});
        }
        core->godot_pool_vector3_array_read_access_destroy(vr);
        core->godot_pool_vector3_array_destroy(&verts);
        if (skinned) {
            const std::size_t joints = out.joints.size(), weights = out.weights.size();
            if (!append_numbers(arrays[kArrayBones], out.joints) ||
                !append_numbers(arrays[kArrayWeights], out.weights) ||
                out.joints.size() - joints != 4 * std::size_t(nv) ||
                out.weights.size() - weights != 4 * std::size_t(nv)) {
                why = "surface " + std::to_string(s) + " lacks 4 bone indices and 4 weights a vertex";
                return false;
            }
        }
        std::vector<std::int32_t> idx;
        if (append_numbers(arrays[kArrayIndex], idx) && !idx.empty()) {
            for (std::size_t i = 0; i + 2 < idx.size(); i += 3) {
                out.indices.insert(out.indices.end(),
                                   {base + std::uint32_t(idx[i]), base + std::uint32_t(idx[i + 1]),
                                    base + std::uint32_t(idx[i + 2])});
            }
            continue;
        }
        for (godot_int i = 0; i + 2 < nv; i += 3) {
            out.indices.insert(out.indices.end(), {base + std::uint32_t(i), base + std::uint32_t(i + 1),
                                                   base + std::uint32_t(i + 2)});
        }
    }
    if (out.indices.empty()) {
        why = "has no triangles";
        return false;
    }
    return true;
}

std::string node_path(godot_object* node) {
    return call(node, "Node", "get_path").as_string();
}

Mat4 to_mat4(const Var& transform) {
    Mat4 m;
    to_column_major(transform.as_transform(), m.m);
    return m;
}

// The Skeleton a MeshInstance's skeleton path leads to, or null.
godot_object* skeleton_of(godot_object* node) {
    Var path = call(node, "MeshInstance", "get_skeleton_path");
    godot_object* target = call(node, "Node", "get_node_or_null", {&path}).object();
    return is_class(target, "Skeleton") ? target : nullptr;
}

// True when some surface of an ArrayMesh carries bone indices and weights (PrimitiveMeshes carry none).
bool has_bone_weights(godot_object* mesh) {
    if (!is_class(mesh, "ArrayMesh")) {
        return false;
    }
    const std::int64_t surfaces = call(mesh, "Mesh", "get_surface_count").as_int();
    for (std::int64_t s = 0; s < surfaces; ++s) {
        Var index(s);
        const std::int64_t format = call(mesh, "ArrayMesh", "surface_get_format", {&index}).as_int();
        if ((format & kArrayFormatBones) != 0 && (format & kArrayFormatWeights) != 0) {
            return true;
        }
    }
    return false;
}

// The binds of `skin` on `skeleton` (a bind names its bone, or gives its index), or Godot's default skin
// from the skeleton's rests when the MeshInstance has no Skin. False with the reason in `why`.
bool skin_binds(godot_object* skin, godot_object* skeleton, std::vector<integration::SkinBind>& binds,
                std::string& why) {
    const std::int64_t bones = call(skeleton, "Skeleton", "get_bone_count").as_int();
    if (skin == nullptr) {
        std::vector<Mat4> rests(std::size_t(std::max<std::int64_t>(bones, 0)));
        std::vector<std::int32_t> parents(rests.size());
        for (std::size_t i = 0; i < rests.size(); ++i) {
            Var bone{std::int64_t(i)};
            rests[i] = to_mat4(call(skeleton, "Skeleton", "get_bone_rest", {&bone}));
            parents[i] = std::int32_t(call(skeleton, "Skeleton", "get_bone_parent", {&bone}).as_int());
        }
        if (Outcome o = integration::default_skin(rests, parents, binds); !o) {
            why = "the skeleton's default skin: " + o.message();
            return false;
        }
        return true;
    }
    const std::int64_t count = call(skin, "Skin", "get_bind_count").as_int();
    binds.assign(std::size_t(std::max<std::int64_t>(count, 0)), {});
    for (std::size_t i = 0; i < binds.size(); ++i) {
        Var index{std::int64_t(i)};
        Var name = call(skin, "Skin", "get_bind_name", {&index});
        const std::string bone_name = name.as_string();
        if (bone_name.empty()) {
            binds[i].bone = std::int32_t(call(skin, "Skin", "get_bind_bone", {&index}).as_int());
        } else {
            binds[i].bone = std::int32_t(call(skeleton, "Skeleton", "find_bone", {&name}).as_int());
            if (binds[i].bone < 0) {
                why =
                    "bind " + std::to_string(i) + " names bone '" + bone_name + "', which the skeleton lacks";
                return false;
            }
        }
        if (binds[i].bone < 0 || binds[i].bone >= bones) {
            why = "bind " + std::to_string(i) + " follows bone " + std::to_string(binds[i].bone) +
                  ", the skeleton has " + std::to_string(bones);
            return false;
        }
        binds[i].pose = to_mat4(call(skin, "Skin", "get_bind_pose", {&index}));
    }
    return true;
}

// A skinned MeshInstance: its bind pose and skin uploaded once (again when its Mesh, Skin, Skeleton or bind
// count changes), its palette from the skeleton's bone poses every frame. False when gust refuses it (the
// reason is logged once): the caller then takes it in its rest pose.
bool report_skinned(Wind& w, godot_object* node, std::uint64_t id, godot_object* mesh, godot_object* skeleton,
                    godot_object* skin) {
    auto refuse = [&](const std::string& why) {
        report_once(w, id,
                    "skinned MeshInstance " + node_path(node) + ": " + why + ": taken in its rest pose");
        return false;
    };
    std::vector<integration::SkinBind> binds;
    std::string why;
    if (!skin_binds(skin, skeleton, binds, why)) {
        return refuse(why);
    }
    Skinned now;
    now.mesh = instance_id(mesh);
    now.skin = skin != nullptr ? instance_id(skin) : 0;
    now.skeleton = instance_id(skeleton);
    now.joints = binds.size();
    Skinned& s = w.skinned[id];
    s.seen = true;
    if (s.mesh != now.mesh || s.skin != now.skin || s.skeleton != now.skeleton || s.joints != now.joints) {
        s = now;
        s.seen = true;
        MeshArrays arrays;
        if (!read_mesh(mesh, true, arrays, why)) {
            s.refused = true;
            return refuse("its Mesh " + why);
        }
        integration::SkinnedMeshData data{arrays.positions, arrays.indices, arrays.joints, arrays.weights,
                                          std::uint32_t(std::min<std::size_t>(binds.size(), 0xffffffffu))};
        const std::uint64_t key = w.next_skinned_key++;
        if (Outcome o = w.host.add_skinned_mesh(key, data); !o) {
            s.refused = true;
            return refuse(o.message());
        }
        s.key = key;
    }
    if (s.refused) {
        return false;
    }
    const std::int64_t bones = call(skeleton, "Skeleton", "get_bone_count").as_int();
    std::vector<Mat4> poses(std::size_t(std::max<std::int64_t>(bones, 0)));
    for (std::size_t i = 0; i < poses.size(); ++i) {
        Var bone{std::int64_t(i)};
        poses[i] = to_mat4(call(skeleton, "Skeleton", "get_bone_global_pose", {&bone}));
    }
    std::vector<Mat4> palette;
    Outcome o = integration::skin_palette(poses, binds, palette);
    if (o) {
        o = w.host.set_bones(s.key, palette);
    }
    if (!o) {
        s.refused = true;
        return refuse(o.message());
    }
    if (Outcome r = w.host.report_obstacle(id, s.key, to_mat4(call(node, "Spatial", "get_global_transform")));
        !r) {
        report_once(w, id, "MeshInstance " + node_path(node) + ": " + r.message());
    }
    return true;
}

void report_obstacles(Wind& w, godot_object* tree) {
    Var group(w.obstacle_group.c_str());
    w.host.begin_obstacles();
    for (auto& [id, s] : w.skinned) {
        s.seen = false;
    }
    for (const Var& item : array_items(call(tree, "SceneTree", "get_nodes_in_group", {&group}))) {
        godot_object* node = item.object();
        const std::uint64_t id = instance_id(node);
        if (!is_class(node, "MeshInstance")) {
            report_once(w, id,
                        "node " + node_path(node) + " in group '" + w.obstacle_group + "' is a " +
                            call(node, "Object", "get_class").as_string() + ", not a MeshInstance: ignored");
            continue;
        }
        godot_object* mesh = call(node, "MeshInstance", "get_mesh").object();
        if (mesh == nullptr) {
            continue;
        }
        godot_object* skin = call(node, "MeshInstance", "get_skin").object();
        godot_object* skeleton = skeleton_of(node);
        if (skeleton != nullptr && has_bone_weights(mesh)) {
            if (report_skinned(w, node, id, mesh, skeleton, skin)) {
                continue;
            }
        } else if (skin != nullptr) {
            report_once(w, id,
                        "MeshInstance " + node_path(node) + " has a Skin but " +
                            (skeleton == nullptr
                                 ? "its skeleton path '" +
                                       call(node, "MeshInstance", "get_skeleton_path").as_string() +
                                       "' leads to no Skeleton"
                                 : std::string("its Mesh has no bone weights")) +
                            ": taken in its rest pose");
        }
        const std::uint64_t mesh_key = instance_id(mesh);
        if (!w.host.has_mesh(mesh_key)) {
            MeshArrays arrays;
            std::string why;
            if (!read_mesh(mesh, false, arrays, why)) {
                report_once(w, id, "MeshInstance " + node_path(node) + " " + why + ": ignored");
                continue;
            }
            if (Outcome o = w.host.add_mesh(mesh_key, arrays.positions, arrays.indices); !o) {
                report_once(w, id, "MeshInstance " + node_path(node) + ": " + o.message());
                continue;
            }
        }
        if (Outcome o =
                w.host.report_obstacle(id, mesh_key, to_mat4(call(node, "Spatial", "get_global_transform")));
            !o) {
            report_once(w, id, "MeshInstance " + node_path(node) + ": " + o.message());
        }
    }
    w.host.end_obstacles();
    for (auto it = w.skinned.begin(); it != w.skinned.end();) {
        it = it->second.seen ? std::next(it) : w.skinned.erase(it);
    }
}

void report_emitters(Wind& w) {
    std::vector<WindEmitter> emitters;
    for (const Var& child : array_items(call(w.owner, "Node", "get_children"))) {
        WindEmitter e;
        if (emitter_of(child.object(), e) && emitters.size() < 64) {
            emitters.push_back(e);
        }
    }
    if (Outcome o = w.host.set_emitters(emitters); !o) {
        report(w, "emitters: " + o.message());
    }
}

void publish(Wind& w, godot_object* tree) {
    const auto start = std::chrono::steady_clock::now();
    if (Outcome o = w.host.read_field(w.field); !o) {
        return;
    }
    const std::uint32_t* e = w.field.extent;
    if (w.texture.is_nil() || std::memcmp(e, w.texture_extent, sizeof(w.texture_extent)) != 0) {
        w.texture = make("Texture3D");
        Var x{std::int64_t(e[0])}, y{std::int64_t(e[1])}, z{std::int64_t(e[2])};
        Var format(kImageFormatRgbaf), flags(kTextureFlagFilter);
        call(w.texture.object(), "Texture3D", "create", {&x, &y, &z, &format, &flags});
        std::memcpy(w.texture_extent, e, sizeof(w.texture_extent));
    }
    const std::size_t layer_floats = std::size_t(e[0]) * e[1] * 4;
    Var width{std::int64_t(e[0])}, height{std::int64_t(e[1])}, no_mipmaps{false}, format{kImageFormatRgbaf};
    for (std::uint32_t k = 0; k < e[2]; ++k) {
        godot_pool_byte_array bytes;
        core->godot_pool_byte_array_new(&bytes);
        core->godot_pool_byte_array_resize(&bytes, godot_int(layer_floats * sizeof(float)));
        godot_pool_byte_array_write_access* wa = core->godot_pool_byte_array_write(&bytes);
        std::memcpy(core->godot_pool_byte_array_write_access_ptr(wa), w.field.rgba.data() + k * layer_floats,
                    layer_floats * sizeof(float));
        core->godot_pool_byte_array_write_access_destroy(wa);
        godot_variant data;
        core->godot_variant_new_pool_byte_array(&data, &bytes);
        core->godot_pool_byte_array_destroy(&bytes);
        Var data_var(data);
        Var image = make("Image");
        call(image.object(), "Image", "create_from_data", {&width, &height, &no_mipmaps, &format, &data_var});
        Var layer{std::int64_t(k)};
        call(w.texture.object(), "Texture3D", "set_layer_data", {&image, &layer});
    }
    // uvw = (p − origin) / (extent · cell_size): a scale and an offset (Transform: basis rows, then origin).
    float t[12] = {};
    const float* o = &w.field.origin.x;
    for (int a = 0; a < 3; ++a) {
        const float inv = 1.0f / (float(e[a]) * w.field.cell_size);
        t[4 * a] = inv;
        t[9 + a] = -o[a] * inv;
    }
    std::memcpy(&w.world_to_texture, t, sizeof(t));
    Var tex_name("gust_wind"), xf_name("gust_world_to_texture"), xf(w.world_to_texture);
    Var group(w.material_group.c_str());
    std::set<std::uint64_t> done;
    auto apply = [&](const Var& material) {
        godot_object* mat = material.object();
        if (mat != nullptr && is_class(mat, "ShaderMaterial") && done.insert(instance_id(mat)).second) {
            call(mat, "ShaderMaterial", "set_shader_param", {&tex_name, &w.texture});
            call(mat, "ShaderMaterial", "set_shader_param", {&xf_name, &xf});
        }
    };
    for (const Var& item : array_items(call(tree, "SceneTree", "get_nodes_in_group", {&group}))) {
        godot_object* node = item.object();
        if (!is_class(node, "GeometryInstance")) {
            continue;
        }
        apply(call(node, "GeometryInstance", "get_material_override"));
        if (!is_class(node, "MeshInstance")) {
            continue;
        }
        const std::int64_t surfaces = call(node, "MeshInstance", "get_surface_material_count").as_int();
        godot_object* mesh = call(node, "MeshInstance", "get_mesh").object();
        for (std::int64_t s = 0; s < surfaces; ++s) {
            Var index(s);
            apply(call(node, "MeshInstance", "get_surface_material", {&index}));
            if (mesh != nullptr) {
                apply(call(mesh, "Mesh", "surface_get_material", {&index}));
            }
        }
    }
    w.publish_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

bool tick(Wind& w, double dt) {
    godot_object* tree = call(w.owner, "Node", "get_tree").object();
    if (tree == nullptr) {
        return false;
    }
    if (w.dirty) {
        w.dirty = false;
        float m[16];
        to_column_major(call(w.owner, "Spatial", "get_global_transform").as_transform(), m);
        w.config.focus = {m[12], m[13], m[14]};
        std::unique_lock lock(w.shared->mutex);
        Hooks hooks;
        hooks.log = [](void*, LogLevel level, const char* message) {
            if (level == LogLevel::Error) {
                error(message, "GustWind");
            } else if (level == LogLevel::Warning) {
                warning(message, "GustWind");
            }
        };
        if (Outcome o = w.host.create(w.config, hooks); !o) {
            report(w, "no wind: " + o.message());
            return false;
        }
        w.reported.clear();
        w.skinned.clear();
    }
    if (!w.host.alive()) {
        return false;
    }
    report_obstacles(w, tree);
    report_emitters(w);
    if (Outcome o = w.host.step(float(dt)); !o) {
        report(w, "step: " + o.message());
        return false;
    }
    w.last_error.clear();
    publish(w, tree);
    return true;
}

Vec3 to_vec3(const godot_vector3& v) {
    const Float3 f = to_float3(v);
    return {f.x, f.y, f.z};
}

godot_variant m_physics_process(godot_object*, void*, void* u, int argc, godot_variant** argv) {
    Wind& w = self(u);
    if (w.auto_step && argc == 1) {
        tick(w, core->godot_variant_as_real(argv[0]));
    }
    return Var().release();
}

godot_variant m_step(godot_object*, void*, void* u, int argc, godot_variant** argv) {
    const double dt = argc == 1 ? core->godot_variant_as_real(argv[0]) : 0.0;
    return Var(tick(self(u), dt)).release();
}

godot_variant m_exit_tree(godot_object*, void*, void* u, int, godot_variant**) {
    Wind& w = self(u);
    std::unique_lock lock(w.shared->mutex);
    w.host.destroy();
    w.dirty = true;
    return Var().release();
}

// The wind at one Vector3 argument, from any thread.
godot_variant wind_at(Shared& shared, const char* what, int argc, godot_variant** argv) {
    if (argc != 1 || core->godot_variant_get_type(argv[0]) != GODOT_VARIANT_TYPE_VECTOR3) {
        error(std::string(what) + ".wind_at takes one Vector3", what);
        return Var(to_vector3(0, 0, 0)).release();
    }
    const Vec3 p = to_vec3(core->godot_variant_as_vector3(argv[0]));
    Vec3 v{};
    std::shared_lock lock(shared.mutex);
    shared.host.sample({&p, 1}, {&v, 1}, shared.ambient);
    return Var(to_vector3(v.x, v.y, v.z)).release();
}

// The wind at each point of one PoolVector3Array argument, from any thread.
godot_variant sample(Shared& shared, const char* what, int argc, godot_variant** argv) {
    godot_pool_vector3_array out;
    core->godot_pool_vector3_array_new(&out);
    if (argc != 1 || core->godot_variant_get_type(argv[0]) != GODOT_VARIANT_TYPE_POOL_VECTOR3_ARRAY) {
        error(std::string(what) + ".sample takes one PoolVector3Array", what);
    } else {
        godot_pool_vector3_array in = core->godot_variant_as_pool_vector3_array(argv[0]);
        const godot_int n = core->godot_pool_vector3_array_size(&in);
        std::vector<Vec3> points(static_cast<std::size_t>(n));
        std::vector<Vec3> velocities(points.size());
        godot_pool_vector3_array_read_access* r = core->godot_pool_vector3_array_read(&in);
        const godot_vector3* p = core->godot_pool_vector3_array_read_access_ptr(r);
        for (godot_int i = 0; i < n; ++i) {
            points[std::size_t(i)] = to_vec3(p[i]);
        }
        core->godot_pool_vector3_array_read_access_destroy(r);
        core->godot_pool_vector3_array_destroy(&in);
        {
            std::shared_lock lock(shared.mutex);
            shared.host.sample(points, velocities, shared.ambient);
        }
        core->godot_pool_vector3_array_resize(&out, n);
        godot_pool_vector3_array_write_access* wa = core->godot_pool_vector3_array_write(&out);
        godot_vector3* q = core->godot_pool_vector3_array_write_access_ptr(wa);
        for (godot_int i = 0; i < n; ++i) {
            const Vec3& v = velocities[std::size_t(i)];
            q[i] = to_vector3(v.x, v.y, v.z);
        }
        core->godot_pool_vector3_array_write_access_destroy(wa);
    }
    godot_variant result;
    core->godot_variant_new_pool_vector3_array(&result, &out);
    core->godot_pool_vector3_array_destroy(&out);
    return result;
}

godot_variant m_wind_at(godot_object*, void*, void* u, int argc, godot_variant** argv) {
    return wind_at(*self(u).shared, kClass, argc, argv);
}

godot_variant m_sample(godot_object*, void*, void* u, int argc, godot_variant** argv) {
    return sample(*self(u).shared, kClass, argc, argv);
}

godot_variant m_get_steps(godot_object*, void*, void* u, int, godot_variant**) {
    return Var(std::int64_t(self(u).host.steps())).release();
}
godot_variant m_get_moving_obstacles(godot_object*, void*, void* u, int, godot_variant**) {
    return Var(std::int64_t(self(u).host.moving_obstacles())).release();
}
godot_variant m_get_step_ms(godot_object*, void*, void* u, int, godot_variant**) {
    return Var(self(u).host.last_step_ms()).release();
}
godot_variant m_get_publish_ms(godot_object*, void*, void* u, int, godot_variant**) {
    return Var(self(u).publish_ms).release();
}
godot_variant m_get_device_name(godot_object*, void*, void* u, int, godot_variant**) {
    return Var(self(u).host.device_name().c_str()).release();
}
godot_variant m_get_wind_texture(godot_object*, void*, void* u, int, godot_variant**) {
    return Var(self(u).texture).release();
}
godot_variant m_get_world_to_texture(godot_object*, void*, void* u, int, godot_variant**) {
    return Var(self(u).world_to_texture).release();
}

// GustSampler (Reference): a reader of one GustWind for one thread. Godot 3.2 records the method a
// NativeScript instance runs in the instance itself (in builds with DEBUG_ENABLED, such as Debian's), so two
// threads calling the same instance at once race there and crash Godot; a thread other than the main one
// samples through its own GustSampler (docs/godot.md "Threading").
constexpr char kSamplerClass[] = "GustSampler";

struct Sampler {
    std::shared_ptr<Shared> shared;
};

Sampler& sampler(void* user) {
    return *static_cast<Sampler*>(user);
}

godot_variant m_sampler_set_wind(godot_object*, void*, void* u, int argc, godot_variant** argv) {
    void* wind = argc == 1 && core->godot_variant_get_type(argv[0]) == GODOT_VARIANT_TYPE_OBJECT
                     ? userdata_if(core->godot_variant_as_object(argv[0]), &kTypeTag)
                     : nullptr;
    if (wind == nullptr) {
        error("GustSampler.set_wind takes a GustWind", kSamplerClass);
        return Var(false).release();
    }
    sampler(u).shared = self(wind).shared;
    return Var(true).release();
}

godot_variant m_sampler_wind_at(godot_object*, void*, void* u, int argc, godot_variant** argv) {
    Sampler& s = sampler(u);
    if (!s.shared) {
        error("GustSampler has no GustWind (set_wind)", kSamplerClass);
        return Var(to_vector3(0, 0, 0)).release();
    }
    return wind_at(*s.shared, kSamplerClass, argc, argv);
}

godot_variant m_sampler_sample(godot_object*, void*, void* u, int argc, godot_variant** argv) {
    Sampler& s = sampler(u);
    if (!s.shared) {
        error("GustSampler has no GustWind (set_wind)", kSamplerClass);
        Shared none;
        return sample(none, kSamplerClass, argc, argv);
    }
    return sample(*s.shared, kSamplerClass, argc, argv);
}

} // namespace

void register_gust_wind(void* handle) {
    godot_instance_create_func create{};
    create.create_func = [](godot_object* owner, void*) -> void* {
        auto* w = new Wind;
        w->owner = owner;
        return w;
    };
    godot_instance_destroy_func destroy{};
    destroy.destroy_func = [](godot_object*, void*, void* u) {
        auto* w = static_cast<Wind*>(u);
        {
            // A GustSampler may hold the shared state longer: the System goes with the node.
            std::unique_lock lock(w->shared->mutex);
            w->host.destroy();
        }
        delete w;
    };
    nativescript->godot_nativescript_register_class(handle, kClass, "Spatial", create, destroy);
    nativescript11->godot_nativescript_set_type_tag(handle, kClass, &kTypeTag);

    register_property(handle, kClass, "cells", Var(to_vector3(32, 16, 32)), GODOT_PROPERTY_HINT_NONE, "",
                      set_cells, get_cells);
    register_property(handle, kClass, "cell_size", Var(1.0), GODOT_PROPERTY_HINT_NONE, "", set_cell_size,
                      get_cell_size);
    register_property(handle, kClass, "voxels_per_cell", Var(std::int64_t(4)), GODOT_PROPERTY_HINT_RANGE,
                      "1,8", set_voxels, get_voxels);
    register_property(handle, kClass, "ambient", Var(to_vector3(0, 0, 0)), GODOT_PROPERTY_HINT_NONE, "",
                      set_ambient, get_ambient);
    register_property(handle, kClass, "quality", Var(std::int64_t(1)), GODOT_PROPERTY_HINT_ENUM,
                      "Low,Medium,High", set_quality, get_quality);
    register_property(handle, kClass, "obstacle_group", Var("gust_obstacles"), GODOT_PROPERTY_HINT_NONE, "",
                      set_obstacle_group, get_obstacle_group);
    register_property(handle, kClass, "material_group", Var("gust_wind_materials"), GODOT_PROPERTY_HINT_NONE,
                      "", set_material_group, get_material_group);
    register_property(handle, kClass, "auto_step", Var(true), GODOT_PROPERTY_HINT_NONE, "", set_auto_step,
                      get_auto_step);

    register_method(handle, kClass, "_physics_process", m_physics_process);
    register_method(handle, kClass, "_exit_tree", m_exit_tree);
    register_method(handle, kClass, "step", m_step);
    register_method(handle, kClass, "wind_at", m_wind_at);
    register_method(handle, kClass, "sample", m_sample);
    register_method(handle, kClass, "get_steps", m_get_steps);
    register_method(handle, kClass, "get_moving_obstacles", m_get_moving_obstacles);
    register_method(handle, kClass, "get_step_ms", m_get_step_ms);
    register_method(handle, kClass, "get_publish_ms", m_get_publish_ms);
    register_method(handle, kClass, "get_device_name", m_get_device_name);
    register_method(handle, kClass, "get_wind_texture", m_get_wind_texture);
    register_method(handle, kClass, "get_world_to_texture", m_get_world_to_texture);

    godot_instance_create_func create_sampler{};
    create_sampler.create_func = [](godot_object*, void*) -> void* { return new Sampler; };
    godot_instance_destroy_func destroy_sampler{};
    destroy_sampler.destroy_func = [](godot_object*, void*, void* u) { delete static_cast<Sampler*>(u); };
    nativescript->godot_nativescript_register_class(handle, kSamplerClass, "Reference", create_sampler,
                                                    destroy_sampler);
    register_method(handle, kSamplerClass, "set_wind", m_sampler_set_wind);
    register_method(handle, kSamplerClass, "wind_at", m_sampler_wind_at);
    register_method(handle, kSamplerClass, "sample", m_sampler_sample);
}

} // namespace gust::godot
